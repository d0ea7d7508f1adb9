// Paths through a map's air (maps/air_paths.hpp): as the crow flies in an open room,
// around a wall by its door (a wall thinner than a voxel included), straight through
// glass and player clip, never beyond the bound; a randomized check that in an empty
// room every path is the straight line within the grid's own error.

#include "dsoc/maps/air_paths.hpp"
#include "dsoc/maps/map_spec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace dsoc::maps {
namespace {

/// A closed room 2048 x 1024 x 256 inside (x -1024..1024, y -512..512, z 0..256), walls
/// 16 thick, and `inside` (more brush lines) added.
Map room(const std::string& inside = "") {
    const std::string text = "dsoc-map 1\n"
                             "name room\n"
                             "box solid -1040 -528 -16 1040 528 0\n"   // floor
                             "box solid -1040 -528 256 1040 528 272\n" // ceiling
                             "box solid -1040 -528 0 -1024 528 256\n"
                             "box solid 1024 -528 0 1040 528 256\n"
                             "box solid -1024 -528 0 1024 -512 256\n"
                             "box solid -1024 512 0 1024 528 256\n"
                             "spawn 0 0 25\n" +
                             inside;
    const auto spec = parse_text_map(text, "room");
    EXPECT_TRUE(spec.ok()) << spec.error().message();
    return build_map(spec.value(), "room");
}

/// The shortest way from a to b round the end of a wall at x = 0 whose gap is at
/// y >= gap_y (both points below it): through the gap's corner.
float round_the_corner(glm::vec3 a, glm::vec3 b, float gap_y) {
    const glm::vec3 corner{0.0f, gap_y, a.z};
    return glm::length(corner - a) + glm::length(b - corner);
}

float path(const AirGrid& grid, glm::vec3 a, glm::vec3 b, float bound = 4000.0f) {
    const std::vector<glm::vec3> to{b};
    return AirPathSearch(grid).lengths(a, to, bound)[0];
}

// A 26-neighbour path is at most 12.8% longer than the line it follows (the worst
// direction is near (41, 17, 13): 13 sqrt(3) + 4 sqrt(2) + 24 against its length), and
// its ends are voxel centres, up to half a voxel's diagonal from the points.
constexpr float kGridStretch = 1.13f;
float longest_grid_path(float straight, float voxel) {
    const float end = std::sqrt(3.0f) * voxel; // both ends' half diagonals
    return kGridStretch * (straight + end) + end;
}

TEST(AirPaths, InAnOpenRoomAPathIsTheStraightLine) {
    const AirGrid grid = air_grid(room(), 16.0f);
    const glm::vec3 a{-600.0f, -100.0f, 80.0f};
    const glm::vec3 b{600.0f, 200.0f, 120.0f};
    const float straight = glm::length(b - a);
    const float p = path(grid, a, b);
    EXPECT_GE(p, straight - std::sqrt(3.0f) * 16.0f);
    EXPECT_LE(p, longest_grid_path(straight, 16.0f));
}

TEST(AirPaths, AWallIsGoneRoundByItsDoorEvenWhenThinnerThanAVoxel) {
    for (const char* wall :
         {"box solid -2 -512 0 2 352 256\n", "box solid -24 -512 0 24 352 256\n"}) {
        const AirGrid grid = air_grid(room(wall), 16.0f);
        const glm::vec3 a{-400.0f, -300.0f, 80.0f};
        const glm::vec3 b{400.0f, -300.0f, 80.0f};
        const float around = round_the_corner(a, b, 352.0f);
        const float p = path(grid, a, b);
        EXPECT_GT(p, 0.97f * around) << wall; // never through the wall
        EXPECT_LE(p, longest_grid_path(around, 16.0f)) << wall;
        EXPECT_GT(p, 1.5f * glm::length(b - a)) << wall;
    }
}

TEST(AirPaths, GlassAndPlayerClipLetSoundThrough) {
    for (const char* wall : {"box glass -2 -512 0 2 512 256\n", "box clip -2 -512 0 2 512 256\n"}) {
        const AirGrid grid = air_grid(room(wall), 16.0f);
        const glm::vec3 a{-400.0f, 0.0f, 80.0f};
        const glm::vec3 b{400.0f, 0.0f, 80.0f};
        EXPECT_LE(path(grid, a, b), longest_grid_path(800.0f, 16.0f)) << wall;
    }
    // And a solid one, sealed, stops it.
    const AirGrid sealed = air_grid(room("box solid -2 -512 0 2 512 256\n"), 16.0f);
    EXPECT_EQ(path(sealed, {-400.0f, 0.0f, 80.0f}, {400.0f, 0.0f, 80.0f}), kNoAirPath);
}

TEST(AirPaths, APathLongerThanTheBoundIsNone) {
    const AirGrid grid = air_grid(room(), 16.0f);
    const glm::vec3 a{-600.0f, 0.0f, 80.0f};
    const glm::vec3 b{600.0f, 0.0f, 80.0f};
    EXPECT_EQ(path(grid, a, b, 1000.0f), kNoAirPath);
    EXPECT_LT(path(grid, a, b, 1400.0f), 1400.0f);
}

TEST(AirPaths, InAnEmptyRoomEveryPathIsItsLineWithinTheGridsError) {
    const float voxel = 16.0f;
    const AirGrid grid = air_grid(room(), voxel);
    AirPathSearch search(grid); // one search reused: what one path reached is forgotten
    std::mt19937 rng(22);
    std::uniform_real_distribution<float> x(-1000.0f, 1000.0f);
    std::uniform_real_distribution<float> y(-490.0f, 490.0f);
    std::uniform_real_distribution<float> z(20.0f, 236.0f);
    for (int i = 0; i < 40; ++i) {
        const glm::vec3 a{x(rng), y(rng), z(rng)};
        std::vector<glm::vec3> to;
        for (int j = 0; j < 10; ++j) {
            to.push_back({x(rng), y(rng), z(rng)});
        }
        const std::vector<float> lengths = search.lengths(a, to, 4000.0f);
        for (std::size_t j = 0; j < to.size(); ++j) {
            const float straight = glm::length(to[j] - a);
            EXPECT_GE(lengths[j], straight - std::sqrt(3.0f) * voxel) << i << " " << j;
            EXPECT_LE(lengths[j], longest_grid_path(straight, voxel)) << i << " " << j;
        }
    }
}

TEST(AirPaths, AGridTooLargeOrAVoxelNotPositiveIsRefusedNamingTheMap) {
    const Map map = room();
    for (const float voxel : {0.0f, -4.0f, 0.01f}) {
        try {
            (void)air_grid(map, voxel);
            ADD_FAILURE() << "voxel " << voxel << " accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("room"), std::string::npos) << e.what();
        }
    }
}

} // namespace
} // namespace dsoc::maps
