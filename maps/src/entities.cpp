#include "dsoc/maps/entities.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

namespace dsoc::maps {
namespace {

constexpr const char* kLump = "entities (lump 0)";

void skip_space(std::string_view text, std::size_t& at) {
    while (at < text.size()) {
        const char c = text[at];
        if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
            ++at;
        } else if (c == '/' && at + 1 < text.size() && text[at + 1] == '/') {
            while (at < text.size() && text[at] != '\n') {
                ++at;
            }
        } else {
            return;
        }
    }
}

/// Reads a quoted string at `at`. Returns false at a missing quote.
bool read_quoted(std::string_view text, std::size_t& at, std::string& out) {
    if (at >= text.size() || text[at] != '"') {
        return false;
    }
    const std::size_t close = text.find('"', at + 1);
    if (close == std::string_view::npos) {
        return false;
    }
    out.assign(text.substr(at + 1, close - at - 1));
    at = close + 1;
    return true;
}

bool parse_floats(std::string_view text, float* out, int count) {
    std::string copy(text);
    const char* cursor = copy.c_str();
    for (int i = 0; i < count; ++i) {
        char* end = nullptr;
        const double value = std::strtod(cursor, &end);
        if (end == cursor || !std::isfinite(value) || std::fabs(value) > 1.0e7) {
            return false;
        }
        out[i] = static_cast<float>(value);
        cursor = end;
    }
    return true;
}

} // namespace

std::string_view Entity::value(std::string_view key) const {
    for (auto it = pairs.rbegin(); it != pairs.rend(); ++it) {
        if (it->first == key) {
            return it->second;
        }
    }
    return {};
}

Result<std::vector<Entity>> parse_entities(std::string_view text, const std::string& file) {
    std::vector<Entity> entities;
    std::size_t at = 0;
    auto fail = [&](const std::string& what) {
        return LoadError{file, kLump, what + " at byte " + std::to_string(at)};
    };
    for (;;) {
        skip_space(text, at);
        if (at >= text.size()) {
            return entities;
        }
        if (text[at] != '{') {
            return fail("expected '{'");
        }
        ++at;
        Entity entity;
        for (;;) {
            skip_space(text, at);
            if (at >= text.size()) {
                return fail("unterminated entity (missing '}')");
            }
            if (text[at] == '}') {
                ++at;
                break;
            }
            std::string key;
            std::string value;
            if (!read_quoted(text, at, key)) {
                return fail("expected a quoted key");
            }
            skip_space(text, at);
            if (!read_quoted(text, at, value)) {
                return fail("expected a quoted value for key \"" + key + "\"");
            }
            entity.pairs.emplace_back(std::move(key), std::move(value));
        }
        entities.push_back(std::move(entity));
    }
}

Result<std::vector<SpawnPoint>> spawn_points_from(const std::vector<Entity>& entities,
                                                  const std::string& file) {
    static constexpr const char* kSpawnClasses[] = {
        "info_player_deathmatch", "info_player_start",  "team_CTF_redspawn",
        "team_CTF_bluespawn",     "team_CTF_redplayer", "team_CTF_blueplayer"};
    std::vector<SpawnPoint> spawns;
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const Entity& entity = entities[i];
        const std::string_view classname = entity.value("classname");
        bool is_spawn = false;
        for (const char* spawn_class : kSpawnClasses) {
            is_spawn = is_spawn || classname == spawn_class;
        }
        if (!is_spawn) {
            continue;
        }
        SpawnPoint spawn;
        spawn.classname = std::string(classname);
        float origin[3] = {0, 0, 0};
        if (!parse_floats(entity.value("origin"), origin, 3)) {
            return LoadError{file, kLump,
                             "entity " + std::to_string(i) + " (" + spawn.classname +
                                 "): origin \"" + std::string(entity.value("origin")) +
                                 "\" is not three finite numbers"};
        }
        spawn.origin = {origin[0], origin[1], origin[2]};
        float angle = 0.0f;
        float angles[3] = {0, 0, 0};
        if (parse_floats(entity.value("angle"), &angle, 1)) {
            spawn.yaw_degrees = angle;
        } else if (parse_floats(entity.value("angles"), angles, 3)) {
            spawn.yaw_degrees = angles[1];
        }
        spawns.push_back(std::move(spawn));
    }
    return spawns;
}

} // namespace dsoc::maps
