#include "dsoc/maps/map_spec.hpp"

#include "brush_builder.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>

namespace dsoc::maps {
namespace {

std::vector<std::string_view> split_words(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t at = 0;
    while (at < line.size()) {
        while (at < line.size() && (line[at] == ' ' || line[at] == '\t' || line[at] == '\r')) {
            ++at;
        }
        const std::size_t start = at;
        while (at < line.size() && line[at] != ' ' && line[at] != '\t' && line[at] != '\r') {
            ++at;
        }
        if (at > start) {
            words.push_back(line.substr(start, at - start));
        }
    }
    return words;
}

std::optional<float> parse_number(std::string_view word) {
    double value = 0.0;
    const auto [end, code] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (code != std::errc() || end != word.data() + word.size() || !std::isfinite(value) ||
        std::fabs(value) > static_cast<double>(kMaxTextCoordinate)) {
        return std::nullopt;
    }
    return static_cast<float>(value);
}

std::optional<BrushKind> parse_kind(std::string_view word) {
    for (const BrushKind kind :
         {BrushKind::solid, BrushKind::glass, BrushKind::caulk, BrushKind::clip}) {
        if (word == to_string(kind)) {
            return kind;
        }
    }
    return std::nullopt;
}

class TextParser {
public:
    TextParser(std::string_view text, const std::string& file) : text_(text), file_(file) {}

    Result<MapSpec> run();

private:
    LoadError fail(const std::string& what) const {
        return {file_, "line " + std::to_string(line_number_), what};
    }
    /// Parses words[first, first + count) as numbers into out.
    bool numbers(const std::vector<std::string_view>& words, std::size_t first, std::size_t count,
                 float* out) const {
        for (std::size_t i = 0; i < count; ++i) {
            const auto value = parse_number(words[first + i]);
            if (!value) {
                return false;
            }
            out[i] = *value;
        }
        return true;
    }
    bool next_line(std::string_view& line) {
        if (at_ >= text_.size()) {
            return false;
        }
        const std::size_t end = text_.find('\n', at_);
        line =
            text_.substr(at_, end == std::string_view::npos ? std::string_view::npos : end - at_);
        at_ = end == std::string_view::npos ? text_.size() : end + 1;
        ++line_number_;
        const std::size_t comment = line.find('#');
        if (comment != std::string_view::npos) {
            line = line.substr(0, comment);
        }
        return true;
    }

    std::string_view text_;
    const std::string& file_;
    std::size_t at_ = 0;
    std::size_t line_number_ = 0;
};

Result<MapSpec> TextParser::run() {
    MapSpec spec;
    bool have_header = false;
    std::string_view line;
    while (next_line(line)) {
        const auto words = split_words(line);
        if (words.empty()) {
            continue;
        }
        const std::string_view keyword = words[0];
        if (!have_header) {
            if (keyword != "dsoc-map" || words.size() != 2 || words[1] != "1") {
                return fail("expected the header \"dsoc-map 1\"");
            }
            have_header = true;
        } else if (keyword == "name") {
            if (words.size() != 2) {
                return fail("expected \"name <word>\"");
            }
            spec.name = std::string(words[1]);
        } else if (keyword == "box") {
            float v[6];
            const auto kind = words.size() == 8 ? parse_kind(words[1]) : std::nullopt;
            if (!kind || !numbers(words, 2, 6, v)) {
                return fail("expected \"box <solid|glass|caulk|clip> minx miny minz maxx maxy "
                            "maxz\" with finite numbers");
            }
            if (!(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) {
                return fail("box min must be below max on every axis");
            }
            spec.brushes.push_back(BrushSpec::box(*kind, {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}}));
        } else if (keyword == "brush") {
            const auto kind = words.size() == 3 ? parse_kind(words[1]) : std::nullopt;
            float count_value = 0;
            if (!kind || !numbers(words, 2, 1, &count_value) || count_value < 4 ||
                count_value > static_cast<float>(kMaxPlanesPerBrush) ||
                count_value != std::floor(count_value)) {
                return fail("expected \"brush <solid|glass|caulk|clip> <n>\" with 4 <= n <= 64");
            }
            BrushSpec brush;
            brush.kind = *kind;
            const auto count = static_cast<std::size_t>(count_value);
            while (brush.planes.size() < count) {
                if (!next_line(line)) {
                    return fail("file ends inside a brush: " + std::to_string(brush.planes.size()) +
                                " of " + std::to_string(count) + " planes");
                }
                const auto plane_words = split_words(line);
                if (plane_words.empty()) {
                    continue;
                }
                float p[4];
                if (plane_words.size() != 5 || plane_words[0] != "plane" ||
                    !numbers(plane_words, 1, 4, p)) {
                    return fail("expected \"plane nx ny nz d\" with finite numbers");
                }
                brush.planes.push_back({{p[0], p[1], p[2]}, p[3]});
            }
            spec.brushes.push_back(std::move(brush));
        } else if (keyword == "hazard") {
            float v[6];
            if (words.size() != 7 || !numbers(words, 1, 6, v) ||
                !(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) {
                return fail("expected \"hazard minx miny minz maxx maxy maxz\" with finite "
                            "numbers, min below max");
            }
            spec.hazards.push_back({{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}}, "hazard"});
        } else if (keyword == "spawn") {
            float v[4] = {0, 0, 0, 0};
            if (words.size() < 4 || words.size() > 6 ||
                !numbers(words, 1, words.size() >= 5 ? 4 : 3, v)) {
                return fail("expected \"spawn x y z [yaw [classname]]\" with finite numbers");
            }
            SpawnPoint spawn;
            spawn.origin = {v[0], v[1], v[2]};
            spawn.yaw_degrees = v[3];
            spawn.classname = words.size() == 6 ? std::string(words[5]) : "info_player_deathmatch";
            spec.spawn_points.push_back(std::move(spawn));
        } else {
            return fail("unknown statement \"" + std::string(keyword.substr(0, 32)) + "\"");
        }
    }
    if (!have_header) {
        return LoadError{file_, "", "empty file (expected the header \"dsoc-map 1\")"};
    }
    return spec;
}

} // namespace

const char* to_string(BrushKind kind) noexcept {
    switch (kind) {
    case BrushKind::solid:
        return "solid";
    case BrushKind::glass:
        return "glass";
    case BrushKind::caulk:
        return "caulk";
    case BrushKind::clip:
        return "clip";
    }
    return "solid";
}

BrushSpec BrushSpec::box(BrushKind kind, const visibility::Aabb& bounds) {
    BrushSpec brush;
    brush.kind = kind;
    brush.planes = {{{1, 0, 0}, bounds.max.x}, {{-1, 0, 0}, -bounds.min.x},
                    {{0, 1, 0}, bounds.max.y}, {{0, -1, 0}, -bounds.min.y},
                    {{0, 0, 1}, bounds.max.z}, {{0, 0, -1}, -bounds.min.z}};
    return brush;
}

Result<MapSpec> parse_text_map(std::string_view text, const std::string& file) {
    return TextParser(text, file).run();
}

Result<MapSpec> read_text_map_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return LoadError{path.string(), "", "cannot open file"};
    }
    std::ostringstream content;
    content << in.rdbuf();
    return parse_text_map(content.str(), path.string());
}

std::string format_text_map(const MapSpec& spec) {
    std::ostringstream out;
    out << std::setprecision(9);
    out << "dsoc-map 1\nname " << spec.name << "\n";
    for (const BrushSpec& brush : spec.brushes) {
        out << "brush " << to_string(brush.kind) << ' ' << brush.planes.size() << '\n';
        for (const visibility::Plane& plane : brush.planes) {
            out << "plane " << plane.normal.x << ' ' << plane.normal.y << ' ' << plane.normal.z
                << ' ' << plane.distance << '\n';
        }
    }
    for (const SpawnPoint& spawn : spec.spawn_points) {
        out << "spawn " << spawn.origin.x << ' ' << spawn.origin.y << ' ' << spawn.origin.z << ' '
            << spawn.yaw_degrees << ' ' << spawn.classname << '\n';
    }
    for (const Hazard& hazard : spec.hazards) {
        out << "hazard " << hazard.bounds.min.x << ' ' << hazard.bounds.min.y << ' '
            << hazard.bounds.min.z << ' ' << hazard.bounds.max.x << ' ' << hazard.bounds.max.y
            << ' ' << hazard.bounds.max.z << '\n';
    }
    return out.str();
}

Map build_map(const MapSpec& spec, std::string source) {
    Map map;
    map.name = spec.name;
    map.source = std::move(source);
    map.stats.brushes_total = spec.brushes.size();
    map.stats.world_brushes = spec.brushes.size();
    for (const BrushSpec& brush : spec.brushes) {
        std::uint32_t contents = 0;
        switch (brush.kind) {
        case BrushKind::solid:
        case BrushKind::caulk:
            contents = contents_solid;
            break;
        case BrushKind::glass:
            contents = contents_solid | contents_translucent;
            break;
        case BrushKind::clip:
            contents = contents_player_clip;
            break;
        }
        if (brush.kind == BrushKind::glass) {
            ++map.stats.translucent_skipped;
        } else if (brush.kind == BrushKind::caulk) {
            ++map.stats.nodraw_skipped;
        }
        detail::add_brush(map, brush.planes, contents, brush.kind == BrushKind::solid);
    }
    map.spawn_points = spec.spawn_points;
    map.hazards = spec.hazards;
    detail::finish_map(map);
    return map;
}

} // namespace dsoc::maps
