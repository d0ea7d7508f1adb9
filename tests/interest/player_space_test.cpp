// The space a baked table covers (sim::player_space through interest::
// walking_bake_request) against where walkers really are: wandering bots on a real
// map, every tick, their boxes and their eye regions (as the culler gets them). A box
// or region outside it costs the table's savings there (never correctness: the table
// answers nothing about uncovered cells), so nearly all must be inside.

#include "dsoc/interest/bake_request.hpp"
#include "dsoc/interest/walking_interest.hpp"
#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/player_space.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "support/openarena.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

namespace dsoc::interest {
namespace {

/// Whether every cell of `grid` that `box` touches is marked in `covered`.
bool inside(const visibility::CellGrid& grid, const std::vector<std::uint8_t>& covered,
            const visibility::Aabb& box) {
    glm::ivec3 lo;
    glm::ivec3 hi;
    if (!grid.range_of(box, lo, hi)) {
        return false;
    }
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            for (int x = lo.x; x <= hi.x; ++x) {
                if (covered[grid.index({x, y, z})] == 0) {
                    return false;
                }
            }
        }
    }
    return true;
}

TEST(PlayerSpace, WanderingBotsAndTheirEyeRegionsStayInTheCoveredCells) {
    DSOC_REQUIRE_OPENARENA();
    auto map = maps::load_map("oa_dm4", maps::MapSearch::from_environment());
    ASSERT_TRUE(map.ok()) << map.error().message();
    const sim::MoveConfig move;
    const auto request = walking_bake_request(move);
    ASSERT_TRUE(request.player_space.has_value());
    // The bake's grid: the map's bounds and a margin.
    const auto grid =
        visibility::CellGrid::covering(map->bounds.expanded(maps::kBakeGridMargin), 32.0f);
    const auto covered =
        maps::cells_meeting(grid, maps::player_space_boxes(map.value(), *request.player_space));
    std::size_t covered_count = 0;
    for (const std::uint8_t c : covered) {
        covered_count += c;
    }
    // It leaves space out (or it would buy nothing).
    EXPECT_LT(covered_count, grid.cell_count() * 3 / 4);

    constexpr float kDt = 1.0f / 30.0f;
    constexpr int kLookahead = 5; // 167 ms at 30 Hz, within kCoveredReachSeconds
    visibility::DSOCConfig config;
    config.tick_rate = 30;
    const WalkingInterest walking(config, map.value(), move, nullptr, kLookahead);
    const sim::CollisionWorld world(map->collision_brushes);
    const sim::WanderConfig wander;
    auto bots = sim::spawn_wander_bots(world, move, map->spawn_points, 64, 17);
    std::size_t samples = 0;
    std::size_t boxes_out = 0;
    std::size_t regions_out = 0;
    for (int tick = 0; tick < 30 * 30; ++tick) {
        for (auto& bot : bots) {
            sim::wander_step(bot, world, wander, move, map->spawn_points, map->hazards, kDt);
            const glm::vec3 p = bot.state.position;
            const visibility::Aabb box{p + move.mins, p + move.maxs};
            const glm::vec3 eye = p + glm::vec3(0.0f, 0.0f, move.eye_height);
            const visibility::Aabb region =
                walking.eye_region(eye, std::max(0.0f, -bot.state.velocity.z));
            ++samples;
            boxes_out += inside(grid, covered, box) ? 0 : 1;
            regions_out += inside(grid, covered, region) ? 0 : 1;
        }
    }
    std::printf("oa_dm4: %zu of %zu cells covered; of %zu bot-ticks, %zu boxes and %zu eye "
                "regions left the covered cells\n",
                covered_count, grid.cell_count(), samples, boxes_out, regions_out);
    EXPECT_LE(boxes_out * 200, samples);   // at most 0.5%
    EXPECT_LE(regions_out * 100, samples); // at most 1%
}

} // namespace
} // namespace dsoc::interest
