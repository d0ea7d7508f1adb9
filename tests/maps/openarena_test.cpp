// The 50 OpenArena maps: every one loads; counts agree with an independent reading
// (tests/maps/q3_lump_counts.py), both with see-through shaders told by name and by the
// game's shader scripts (openarena-data's archives); every spawn point is in open space.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/pk3.hpp"
#include "dsoc/maps/q3_map.hpp"
#include "dsoc/maps/q3_shaders.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

namespace dsoc::maps {
namespace {

std::vector<std::string> openarena_maps() {
    auto names = list_pk3_maps(test::kOpenArenaPak);
    return names ? names.value() : std::vector<std::string>{};
}

TEST(OpenArena, AllFiftyMapsLoad) {
    DSOC_REQUIRE_OPENARENA();
    const auto names = openarena_maps();
    EXPECT_EQ(names.size(), 50u);
    for (const std::string& name : names) {
        const auto map = load_q3_map_from_pk3(test::kOpenArenaPak, name);
        ASSERT_TRUE(map.ok()) << map.error().message();
        const MapStats& s = map->stats;
        EXPECT_GT(s.opaque_occluders, 0u) << name;
        EXPECT_EQ(s.opaque_occluders, map->occluders.size()) << name;
        EXPECT_LE(s.opaque_occluders, s.collision_brushes) << name;
        EXPECT_EQ(s.collision_brushes + s.degenerate.total(), s.collision_candidates) << name;
        EXPECT_GT(map->spawn_points.size(), 0u) << name;
        EXPECT_FALSE(map->bounds.is_empty()) << name;
        for (const auto& occluder : map->occluders) {
            EXPECT_TRUE(map->bounds.contains(occluder.bounds())) << name;
        }
    }
}

/// Runs the Python reader (with `scripts_dir`, telling see-through shaders by the shader
/// scripts of the archives there; without, by name) and returns, per map, its key -> count.
std::map<std::string, std::map<std::string, long>>
independent_counts(const std::vector<std::string>& names,
                   const std::optional<std::filesystem::path>& scripts_dir = std::nullopt) {
    std::string command =
        std::string(DSOC_PYTHON3) + " " + DSOC_TEST_MAPS_DIR + "/q3_lump_counts.py";
    // Built by appending (GCC 12 warns falsely on " ..." + a string).
    if (scripts_dir) {
        command += " --scripts-dir ";
        command += scripts_dir->string();
    }
    command += " ";
    command += test::kOpenArenaPak.string();
    for (const std::string& name : names) {
        command += " ";
        command += name;
    }
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
    std::map<std::string, std::map<std::string, long>> out;
    if (!pipe) {
        return out;
    }
    char buffer[4096];
    while (std::fgets(buffer, sizeof buffer, pipe.get()) != nullptr) {
        // One flat JSON object a line: {"brushes": 747, ..., "map": "oa_dm4"}
        const auto object = nlohmann::json::parse(buffer, nullptr, /*allow_exceptions=*/false);
        if (!object.is_object() || !object.contains("map")) {
            continue;
        }
        auto& values = out[object["map"].get<std::string>()];
        for (const auto& [key, value] : object.items()) {
            if (value.is_number_integer()) {
                values[key] = value.get<long>();
            }
        }
    }
    return out;
}

/// Loads every map with `scripts` and expects its stats to be what the Python reader
/// counted (`expected`, read with the same scripts or none), see-through brushes too.
void expect_counts_match(const std::vector<std::string>& names,
                         const std::map<std::string, std::map<std::string, long>>& expected,
                         const ShaderScripts* scripts) {
    ASSERT_EQ(expected.size(), names.size()) << "q3_lump_counts.py did not report every map";
    for (const std::string& name : names) {
        const auto map = load_q3_map_from_pk3(test::kOpenArenaPak, name, scripts);
        ASSERT_TRUE(map.ok()) << map.error().message();
        const auto& want = expected.at(name);
        const MapStats& s = map->stats;
        EXPECT_EQ(static_cast<long>(s.brushes_total), want.at("brushes")) << name;
        EXPECT_EQ(static_cast<long>(s.world_brushes), want.at("world_brushes")) << name;
        EXPECT_EQ(static_cast<long>(s.collision_candidates), want.at("collision_candidates"))
            << name;
        EXPECT_EQ(static_cast<long>(s.opaque_candidates), want.at("opaque_candidates")) << name;
        EXPECT_EQ(static_cast<long>(s.see_through_skipped), want.at("see_through")) << name;
        EXPECT_EQ(static_cast<long>(map->spawn_points.size()), want.at("spawn_points")) << name;
        EXPECT_EQ(static_cast<long>(s.patches_left_out), want.at("patches")) << name;
        EXPECT_EQ(static_cast<long>(s.opaque_patches), want.at("opaque_patches")) << name;
        EXPECT_EQ(static_cast<long>(s.shader_scripts), want.at("shader_scripts")) << name;
        EXPECT_EQ(static_cast<long>(scripts != nullptr ? scripts->size() : 0),
                  want.at("shader_definitions"))
            << name;
    }
}

TEST(OpenArena, CountsMatchIndependentReading) {
    DSOC_REQUIRE_OPENARENA();
    const auto names = openarena_maps();
    expect_counts_match(names, independent_counts(names), nullptr);
}

TEST(OpenArena, CountsMatchIndependentReadingWithShaderScripts) {
    DSOC_REQUIRE_OPENARENA();
    const std::filesystem::path base_dir(kOpenArenaBaseDir);
    if (!std::filesystem::exists(base_dir / "pak0.pk3")) {
        GTEST_SKIP() << "OpenArena's shader scripts not installed (" << base_dir / "pak0.pk3"
                     << " missing; scripts/setup installs openarena-data)";
    }
    // Every archive of the base dir, as the game loads them with the maps.
    std::vector<std::filesystem::path> archives;
    for (const auto& entry : std::filesystem::directory_iterator(base_dir)) {
        std::string extension = entry.path().extension().string();
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (entry.is_regular_file() && extension == ".pk3") {
            archives.push_back(entry.path());
        }
    }
    std::sort(archives.begin(), archives.end());
    const ShaderScriptsRead read = read_shader_scripts(archives);
    // A script that does not read whole is no failure here (the reader must then say the
    // same: shader_scripts 0, names no script defines told by name), but worth seeing.
    for (const LoadError& problem : read.problems) {
        std::printf("note: %s\n", problem.message().c_str());
    }
    ASSERT_GT(read.scripts.size(), 0u) << "no shader defined by the scripts of " << base_dir;
    const auto names = openarena_maps();
    expect_counts_match(names, independent_counts(names, base_dir), &read.scripts);
}

/// Brute force, independent of dsoc::sim's grid: does the box [p + mins, p + maxs]
/// overlap the interior of the brush (every plane, pushed out by the box's support)?
bool box_overlaps(const CollisionBrush& brush, glm::vec3 p, glm::vec3 mins, glm::vec3 maxs) {
    for (const visibility::Plane& plane : brush.planes) {
        glm::vec3 corner;
        for (int a = 0; a < 3; ++a) {
            corner[a] = plane.normal[a] < 0.0f ? maxs[a] : mins[a];
        }
        if (glm::dot(plane.normal, p + corner) - plane.distance >= 0.0f) {
            return false;
        }
    }
    return true;
}

TEST(OpenArena, EverySpawnPointIsInOpenSpace) {
    DSOC_REQUIRE_OPENARENA();
    // A spawn point is "in open space" when its origin is inside no collision brush and
    // the player's box (Quake 3: 30x30x56, mins -15 -15 -24) at the origin raised by
    // Quake 3's 9 units overlaps the interior of no collision brush.
    const glm::vec3 mins(-15.0f, -15.0f, -24.0f);
    const glm::vec3 maxs(15.0f, 15.0f, 32.0f);
    std::size_t spawns = 0;
    for (const std::string& name : openarena_maps()) {
        const auto map = load_q3_map_from_pk3(test::kOpenArenaPak, name);
        ASSERT_TRUE(map.ok()) << map.error().message();
        for (const SpawnPoint& spawn : map->spawn_points) {
            ++spawns;
            EXPECT_TRUE(map->bounds.contains(spawn.origin)) << name << " " << spawn.classname;
            const glm::vec3 raised = spawn.origin + glm::vec3(0, 0, 9);
            for (const Hazard& hazard : map->hazards) {
                EXPECT_FALSE(hazard.bounds.overlaps({raised + mins, raised + maxs}))
                    << name << ": " << spawn.classname << " in hazard " << hazard.reason;
            }
            for (std::size_t b = 0; b < map->collision_brushes.size(); ++b) {
                const CollisionBrush& brush = map->collision_brushes[b];
                EXPECT_FALSE(box_overlaps(brush, spawn.origin, glm::vec3(0), glm::vec3(0)))
                    << name << ": " << spawn.classname << " origin (" << spawn.origin.x << " "
                    << spawn.origin.y << " " << spawn.origin.z << ") inside brush " << b;
                EXPECT_FALSE(box_overlaps(brush, raised, mins, maxs))
                    << name << ": " << spawn.classname << " at (" << spawn.origin.x << " "
                    << spawn.origin.y << " " << spawn.origin.z << ") player box in brush " << b;
            }
        }
    }
    EXPECT_GT(spawns, 1000u);
}

} // namespace
} // namespace dsoc::maps
