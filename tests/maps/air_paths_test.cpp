// Paths through a map's air (maps/air_paths.hpp): as the crow flies in an open room,
// around a wall by its door (a wall thinner than a voxel included), straight through
// glass and player clip, never beyond the bound; a randomized check that in an empty
// room every path is the straight line within the grid's own error.

#include "dsoc/maps/air_paths.hpp"
#include "dsoc/maps/map_spec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <queue>
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

TEST(AirPaths, APointInAWallsVoxelStartsOnItsOwnSideOfTheWall) {
    // A sealed wall 1 unit thick at x 12..13; a point at x 11 is in a voxel the wall
    // makes solid, and the open voxel centre nearest it (x 24) is behind the wall.
    const AirGrid grid = air_grid(room("box solid 12 -512 0 13 512 256\n"), 16.0f);
    ASSERT_NE(grid.solid[grid.index(grid.voxel_of({11.0f, 0.0f, 80.0f}))], 0);
    EXPECT_EQ(path(grid, {11.0f, 0.0f, 80.0f}, {400.0f, 0.0f, 80.0f}), kNoAirPath);
    EXPECT_EQ(path(grid, {400.0f, 0.0f, 80.0f}, {11.0f, 0.0f, 80.0f}), kNoAirPath);
    EXPECT_LT(path(grid, {11.0f, 0.0f, 80.0f}, {-400.0f, 0.0f, 80.0f}), 450.0f);
}

/// The rule written plainly: Dijkstra with a heap over every voxel, a step to any of
/// the 26 neighbours that is open, as is every voxel it grazes. [Units: voxels]
std::vector<float> plain_distances(const AirGrid& grid, glm::ivec3 from) {
    std::vector<float> distance(grid.solid.size(), kNoAirPath);
    using Entry = std::pair<float, std::size_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
    distance[grid.index(from)] = 0.0f;
    open.push({0.0f, grid.index(from)});
    while (!open.empty()) {
        const auto [d, i] = open.top();
        open.pop();
        if (d > distance[i]) {
            continue;
        }
        const glm::ivec3 v{static_cast<int>(i % static_cast<std::size_t>(grid.size.x)),
                           static_cast<int>(i / static_cast<std::size_t>(grid.size.x) %
                                            static_cast<std::size_t>(grid.size.y)),
                           static_cast<int>(i / static_cast<std::size_t>(grid.size.x) /
                                            static_cast<std::size_t>(grid.size.y))};
        for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const glm::ivec3 w = v + glm::ivec3(dx, dy, dz);
                    if (!grid.inside(w) || grid.solid[grid.index(w)] != 0) {
                        continue;
                    }
                    bool clear = true; // every voxel between: a corner of the step's box
                    for (int k = 0; k < 8; ++k) {
                        const glm::ivec3 c{(k & 1) != 0 ? w.x : v.x, (k & 2) != 0 ? w.y : v.y,
                                           (k & 4) != 0 ? w.z : v.z};
                        clear = clear && grid.solid[grid.index(c)] == 0;
                    }
                    const float dw = d + std::sqrt(static_cast<float>(dx * dx + dy * dy + dz * dz));
                    if (clear && dw < distance[grid.index(w)]) {
                        distance[grid.index(w)] = dw;
                        open.push({dw, grid.index(w)});
                    }
                }
            }
        }
    }
    return distance;
}

TEST(AirPaths, TheBucketedSearchAgreesWithAPlainDijkstraOnRandomGrids) {
    std::mt19937 rng(7);
    std::size_t compared = 0;
    std::size_t unreachable = 0;
    for (int round = 0; round < 12; ++round) {
        AirGrid grid;
        grid.voxel = 8.0f;
        grid.size = {18, 14, 9};
        grid.solid.assign(static_cast<std::size_t>(18 * 14 * 9), 0);
        const float density = 0.1f + 0.04f * static_cast<float>(round);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        for (int z = 0; z < grid.size.z; ++z) {
            for (int y = 0; y < grid.size.y; ++y) {
                for (int x = 0; x < grid.size.x; ++x) {
                    const bool outermost = x == 0 || y == 0 || z == 0 || x == grid.size.x - 1 ||
                                           y == grid.size.y - 1 || z == grid.size.z - 1;
                    grid.solid[grid.index({x, y, z})] = outermost || unit(rng) < density ? 1 : 0;
                }
            }
        }
        std::vector<glm::ivec3> open;
        for (int z = 1; z + 1 < grid.size.z; ++z) {
            for (int y = 1; y + 1 < grid.size.y; ++y) {
                for (int x = 1; x + 1 < grid.size.x; ++x) {
                    if (grid.solid[grid.index({x, y, z})] == 0) {
                        open.push_back({x, y, z});
                    }
                }
            }
        }
        AirPathSearch search(grid); // reused: each search forgets the last
        for (int s = 0; s < 6; ++s) {
            const glm::ivec3 from = open[rng() % open.size()];
            std::vector<glm::vec3> to;
            for (const glm::ivec3 v : open) {
                to.push_back(grid.centre_of(v));
            }
            const std::vector<float> fast = search.lengths(grid.centre_of(from), to, 1e6f);
            const std::vector<float> plain = plain_distances(grid, from);
            for (std::size_t k = 0; k < open.size(); ++k) {
                const float expected = plain[grid.index(open[k])];
                if (expected == kNoAirPath) {
                    EXPECT_EQ(fast[k], kNoAirPath);
                    ++unreachable;
                } else {
                    EXPECT_NEAR(fast[k], expected * grid.voxel, 1e-3f * expected * grid.voxel);
                    ++compared;
                }
            }
        }
    }
    // Both outcomes met often: paths found, and places walled off.
    EXPECT_GT(compared, 5000u);
    EXPECT_GT(unreachable, 500u);
}

TEST(AirPaths, ASearchRefusesAGridWhoseOutermostLayerIsOpen) {
    AirGrid grid;
    grid.voxel = 8.0f;
    grid.size = {4, 4, 4};
    grid.solid.assign(64, 0);
    EXPECT_THROW(AirPathSearch{grid}, std::invalid_argument);
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
