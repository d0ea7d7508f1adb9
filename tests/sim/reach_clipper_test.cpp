// The clipped reachable eye region must contain every eye a walking player really
// has over the lookahead: checked against bots' actual future eyes on real maps.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/sim/reach_clipper.hpp"
#include "dsoc/sim/wander_bot.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <filesystem>

namespace dsoc::sim {
namespace {

visibility::Aabb reach_region(const MoveConfig& move, glm::vec3 eye, float seconds) {
    const MotionBound b = motion_bound(move, seconds);
    return {eye - glm::vec3(b.horizontal, b.horizontal, b.down),
            eye + glm::vec3(b.horizontal, b.horizontal, b.up)};
}

class ReachClipperOnMaps : public ::testing::TestWithParam<const char*> {};

TEST_P(ReachClipperOnMaps, ContainsEveryFutureEyeAndClipsSomething) {
    if (!std::filesystem::exists(std::string(maps::kOpenArenaBaseDir) + "/pak1-maps.pk3")) {
        GTEST_SKIP() << "OpenArena maps not installed (scripts/setup installs openarena-081-maps)";
    }
    auto loaded = maps::load_map(GetParam(), maps::MapSearch::from_environment());
    ASSERT_TRUE(loaded) << loaded.error().message();
    const maps::Map& map = loaded.value();
    const MoveConfig move;
    const WanderConfig wander;
    const CollisionWorld world(map.collision_brushes);
    const ReachClipper clipper(map.collision_brushes, move);
    auto bots = spawn_wander_bots(world, move, map.spawn_points, 60, 5);
    constexpr int kLookahead = 5;
    constexpr float kDt = 1.0f / 30.0f;
    // Per bot, the regions predicted over the last kLookahead ticks, checked against
    // the eye each later tick actually has.
    std::vector<std::deque<visibility::Aabb>> pending(bots.size());
    long checks = 0;
    long clipped = 0;
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
            const auto full = reach_region(move, eye, kLookahead * kDt);
            const auto region = clipper.clip(eye, full);
            ASSERT_TRUE(full.contains(region));
            if (region.size() != full.size()) {
                ++clipped;
            }
            volume_ratio += (region.size().x * region.size().y * region.size().z) /
                            (full.size().x * full.size().y * full.size().z);
            pending[i].push_back(region);
            if (pending[i].size() > kLookahead) {
                pending[i].pop_front();
            }
        }
    }
    const double samples = 600.0 * static_cast<double>(bots.size());
    EXPECT_GT(checks, 100000);
    EXPECT_GT(clipped, static_cast<long>(samples * 0.1)) << "the clipper should bite near walls";
    std::printf("%s: %ld future eyes checked, %.0f%% of regions clipped, mean volume kept %.0f%%\n",
                GetParam(), checks, 100.0 * static_cast<double>(clipped) / samples,
                100.0 * volume_ratio / samples);
}

INSTANTIATE_TEST_SUITE_P(Maps, ReachClipperOnMaps,
                         ::testing::Values("oa_dm4", "q3dm6ish", "ctf_inyard"));

} // namespace
} // namespace dsoc::sim
