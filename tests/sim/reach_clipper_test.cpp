// The clipped reachable eye region must contain every eye a walking player really
// has over the lookahead: checked against bots' actual future eyes on real maps. The
// walls found through the clipper's xy columns give the same region as all the walls.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/sim/motion_limits.hpp"
#include "dsoc/sim/reach_clipper.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "support/openarena.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <random>

namespace dsoc::sim {
namespace {

class ReachClipperOnMaps : public ::testing::TestWithParam<const char*> {};

TEST_P(ReachClipperOnMaps, ContainsEveryFutureEyeAndClipsSomething) {
    DSOC_REQUIRE_OPENARENA();
    auto loaded = maps::load_map(GetParam(), maps::MapSearch::from_environment());
    ASSERT_TRUE(loaded) << loaded.error().message();
    const maps::Map& map = loaded.value();
    const MoveConfig move;
    const WanderConfig wander;
    const CollisionWorld world(map.collision_brushes);
    const ReachClipper clipper(map.collision_brushes, move);
    // The slow twin: one column holding every wall, so every region looks at all of them.
    const ReachClipper every_wall(map.collision_brushes, move, 1e9f);
    auto bots = spawn_wander_bots(world, move, map.spawn_points, 60, 5);
    constexpr int kLookahead = 5;
    constexpr float kDt = 1.0f / 30.0f;
    const visibility::MotionLimits limits = walking_limits(move, kDt);
    const float seconds = kLookahead * kDt;
    // Per bot, the regions predicted over the last kLookahead ticks, checked against
    // the eye each later tick actually has.
    std::vector<std::deque<visibility::Aabb>> pending(bots.size());
    long checks = 0;
    long clipped = 0;
    long floors_raised = 0; ///< regions whose floor the no-slope fall law raised
    double volume_ratio = 0.0;
    for (int tick = 0; tick < 600; ++tick) {
        for (std::size_t i = 0; i < bots.size(); ++i) {
            wander_step(bots[i], world, wander, move, map.spawn_points, map.hazards, kDt);
            const glm::vec3 eye = bots[i].state.position + glm::vec3(0, 0, move.eye_height);
            if (bots[i].respawned) { // a teleport is outside the contract
                pending[i].clear();
            }
            for (const auto& region : pending[i]) {
                ASSERT_TRUE(region.expanded(1e-3f).contains(eye))
                    << GetParam() << " tick " << tick << " bot " << i << ": eye (" << eye.x << ", "
                    << eye.y << ", " << eye.z << ") left its predicted region";
                ++checks;
            }
            const float down = std::max(0.0f, -bots[i].state.velocity.z);
            const auto full =
                visibility::reachable_box(visibility::Aabb{eye, eye}, limits, seconds, 1.0f, down);
            const auto walls_only = clipper.clip(eye, full);
            const auto region =
                clipper.clip(eye, full, visibility::EyeReach{&limits, seconds, down});
            const auto same_walls = [](const visibility::Aabb& a, const visibility::Aabb& b) {
                return a.min == b.min && a.max == b.max;
            };
            ASSERT_TRUE(same_walls(walls_only, every_wall.clip(eye, full)));
            ASSERT_TRUE(same_walls(
                region, every_wall.clip(eye, full, visibility::EyeReach{&limits, seconds, down})));
            ASSERT_TRUE(full.contains(walls_only));
            ASSERT_TRUE(walls_only.contains(region));
            if (walls_only.size() != full.size()) {
                ++clipped;
            }
            if (region.min.z > walls_only.min.z + 1.0f) {
                ++floors_raised;
            }
            volume_ratio += (region.size().x * region.size().y * region.size().z) /
                            (full.size().x * full.size().y * full.size().z);
            pending[i].push_back(region);
            if (pending[i].size() > kLookahead) {
                pending[i].pop_front();
            }
        }
    }
    // Eyes scattered around the spawn points (inside walls too) with regions up to
    // twice a tick's reach: the columns still find every wall that clips.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_real_distribution<float> offset(-400.0f, 400.0f);
    long differing_from_input = 0;
    for (int i = 0; i < 5000; ++i) {
        const glm::vec3 spawn = map.spawn_points[rng() % map.spawn_points.size()].origin;
        const glm::vec3 eye = spawn + glm::vec3(offset(rng), offset(rng), offset(rng) / 8.0f);
        const glm::vec3 below(unit(rng) * 120.0f, unit(rng) * 120.0f, unit(rng) * 60.0f);
        const glm::vec3 above(unit(rng) * 120.0f, unit(rng) * 120.0f, unit(rng) * 60.0f);
        const visibility::Aabb region{eye - below, eye + above};
        const auto fast = clipper.clip(eye, region);
        const auto slow = every_wall.clip(eye, region);
        ASSERT_TRUE(fast.min == slow.min && fast.max == slow.max) << GetParam() << " sample " << i;
        differing_from_input += fast.min != region.min || fast.max != region.max ? 1 : 0;
    }
    EXPECT_GT(differing_from_input, 50) << "some random regions should meet walls";
    const double samples = 600.0 * static_cast<double>(bots.size());
    EXPECT_GT(checks, 100000);
    // oa_dm4's open middle leaves few regions at a wall (4% since the bots keep off its
    // ledges, 43-54% on the other maps).
    EXPECT_GT(clipped, static_cast<long>(samples * 0.03)) << "the clipper should bite near walls";
    EXPECT_GT(floors_raised, static_cast<long>(samples * 0.1))
        << "away from slopes the fall is gravity's alone";
    std::printf("%s: %ld future eyes checked, %.0f%% of regions clipped by walls, %.0f%% with the "
                "floor raised (no slope in reach; %zu sloped brushes), mean volume kept %.0f%%\n",
                GetParam(), checks, 100.0 * static_cast<double>(clipped) / samples,
                100.0 * static_cast<double>(floors_raised) / samples, clipper.slope_count(),
                100.0 * volume_ratio / samples);
}

INSTANTIATE_TEST_SUITE_P(Maps, ReachClipperOnMaps,
                         ::testing::Values("oa_dm4", "q3dm6ish", "ctf_inyard", "wrackdm17"));

} // namespace
} // namespace dsoc::sim
