// The movement acceptance test: 200 wandering bots for 60 simulated seconds (30 Hz)
// on several OpenArena maps and on generated worlds. None may end up inside a brush,
// below or outside the world, or move faster than the speed contract allows.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/map_spec.hpp"
#include "dsoc/sim/motion_limits.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "support/openarena.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>

namespace dsoc::sim {
namespace {

constexpr float kDt = 1.0f / 30.0f;
constexpr int kTicks = 60 * 30;
constexpr std::size_t kBots = 200;
constexpr int kWindowTicks = 30; ///< also check the bound over 1-second windows
/// Window lengths (ticks) over which walking_limits() is checked through reachable_box(),
/// from one tick to a second: eye regions and TBVs use these.
constexpr std::array<int, 8> kReachWindows{1, 2, 3, 5, 8, 12, 20, 30};
/// Float rounding of positions a few thousand units from the origin. [Units: world units]
constexpr float kTolerance = 0.01f;

struct RunFigures {
    std::size_t inside_brush = 0;
    std::size_t below_world = 0;
    std::size_t outside_bounds = 0;
    std::size_t over_speed = 0;
    std::size_t over_bound = 0;
    /// Positions outside reachable_box(walking_limits) of an earlier position, with the
    /// downward speed then (the interest manager's TBVs and eye regions).
    std::size_t outside_reach = 0;
    float worst_reach_excess = 0.0f; ///< [Units: world units]
    float fastest_horizontal = 0.0f; ///< [Units: world units/s]
    float fastest_tick_move = 0.0f;  ///< horizontal distance in one tick / dt
    std::size_t goals_reached = 0;
    std::size_t goals_abandoned = 0;
    std::size_t deaths = 0; ///< respawns after touching a hazard
    std::size_t on_ground_at_end = 0;
    float mean_travel = 0.0f; ///< mean horizontal distance walked per bot
};

RunFigures run_bots(const maps::Map& map, std::uint64_t seed) {
    const CollisionWorld world(map.collision_brushes);
    const MoveConfig move;
    const WanderConfig wander;
    std::vector<WanderBot> bots = spawn_wander_bots(world, move, map.spawn_points, kBots, seed);
    RunFigures figures;
    const visibility::Aabb bounds = world.bounds();
    const MotionBound tick_bound = motion_bound(move, kDt);
    const MotionBound window_bound = motion_bound(move, kDt * kWindowTicks);
    std::vector<glm::vec3> window_start(bots.size());
    std::vector<float> travel(bots.size(), 0.0f);
    const visibility::MotionLimits limits = walking_limits(move, kDt);
    struct Sample {
        glm::vec3 position;
        float down_velocity; ///< >= 0
    };
    std::vector<std::deque<Sample>> history(bots.size()); ///< newest first
    for (std::size_t i = 0; i < bots.size(); ++i) {
        window_start[i] = bots[i].state.position;
        EXPECT_FALSE(world.box_in_solid(bots[i].state.position, move.mins, move.maxs))
            << map.name << " bot " << i << " spawned inside a brush";
    }
    for (int tick = 1; tick <= kTicks; ++tick) {
        for (std::size_t i = 0; i < bots.size(); ++i) {
            WanderBot& bot = bots[i];
            const glm::vec3 before = bot.state.position;
            const float down_before = std::max(0.0f, -bot.state.velocity.z);
            wander_step(bot, world, wander, move, map.spawn_points, map.hazards, kDt);
            const glm::vec3 p = bot.state.position;
            if (bot.respawned) { // a teleport: outside the speed contract
                ++figures.deaths;
                history[i].clear();
                window_start[i] = p;
                EXPECT_FALSE(world.box_in_solid(p, move.mins, move.maxs)) << map.name;
                continue;
            }
            const glm::vec3 moved = p - before;
            history[i].push_front({before, down_before});
            history[i].resize(std::min<std::size_t>(history[i].size(), kReachWindows.back()));
            for (const int ticks : kReachWindows) {
                if (static_cast<std::size_t>(ticks) > history[i].size()) {
                    break;
                }
                const Sample& then = history[i][static_cast<std::size_t>(ticks - 1)];
                const visibility::Aabb reach = visibility::reachable_box(
                    visibility::Aabb{then.position, then.position}, limits,
                    static_cast<float>(ticks) * kDt, 1.0f, then.down_velocity);
                const glm::vec3 excess = glm::max(reach.min - p, p - reach.max);
                const float worst = std::max({excess.x, excess.y, excess.z});
                if (worst > kTolerance) {
                    ++figures.outside_reach;
                    figures.worst_reach_excess = std::max(figures.worst_reach_excess, worst);
                }
            }
            const float horizontal = std::hypot(moved.x, moved.y);
            travel[i] += horizontal;
            const float speed = std::hypot(bot.state.velocity.x, bot.state.velocity.y);
            figures.fastest_horizontal = std::max(figures.fastest_horizontal, speed);
            figures.fastest_tick_move = std::max(figures.fastest_tick_move, horizontal / kDt);
            if (speed > move.max_speed + 1e-3f || bot.state.velocity.z > move.jump_velocity ||
                bot.state.velocity.z < -move.max_fall_speed) {
                ++figures.over_speed;
            }
            if (horizontal > tick_bound.horizontal + kTolerance ||
                moved.z > tick_bound.up + kTolerance || -moved.z > tick_bound.down + kTolerance) {
                ++figures.over_bound;
            }
            if (world.box_in_solid(p, move.mins, move.maxs)) {
                ++figures.inside_brush;
            }
            if (p.z + move.mins.z < bounds.min.z) {
                ++figures.below_world;
            }
            if (!bounds.contains(p)) {
                ++figures.outside_bounds;
            }
            if (tick % kWindowTicks == 0) {
                const glm::vec3 w = p - window_start[i];
                if (std::hypot(w.x, w.y) > window_bound.horizontal + kTolerance ||
                    w.z > window_bound.up + kTolerance || -w.z > window_bound.down + kTolerance) {
                    ++figures.over_bound;
                }
                window_start[i] = p;
            }
        }
    }
    for (std::size_t i = 0; i < bots.size(); ++i) {
        figures.goals_reached += bots[i].goals_reached;
        figures.goals_abandoned += bots[i].goals_abandoned;
        figures.mean_travel += travel[i] / static_cast<float>(bots.size());
        figures.on_ground_at_end += bots[i].state.on_ground ? 1 : 0;
    }
    return figures;
}

void check(const maps::Map& map, std::uint64_t seed) {
    const auto start = std::chrono::steady_clock::now();
    const RunFigures f = run_bots(map, seed);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "[ figures  ] %s: %zu bots x %d ticks in %.2f s: inside %zu, below %zu, outside %zu, "
        "over speed %zu, over bound %zu, fastest %.1f u/s (tick move %.1f u/s), goals "
        "reached %zu abandoned %zu, deaths %zu, on ground at end %zu, mean travel %.0f u, "
        "outside reach %zu (worst by %.2f u)\n",
        map.name.c_str(), kBots, kTicks, seconds, f.inside_brush, f.below_world, f.outside_bounds,
        f.over_speed, f.over_bound, f.fastest_horizontal, f.fastest_tick_move, f.goals_reached,
        f.goals_abandoned, f.deaths, f.on_ground_at_end, f.mean_travel, f.outside_reach,
        f.worst_reach_excess);
    EXPECT_EQ(f.inside_brush, 0u) << map.name;
    EXPECT_EQ(f.below_world, 0u) << map.name;
    EXPECT_EQ(f.outside_bounds, 0u) << map.name;
    EXPECT_EQ(f.over_speed, 0u) << map.name;
    EXPECT_EQ(f.over_bound, 0u) << map.name;
    EXPECT_EQ(f.outside_reach, 0u) << map.name << ": worst by " << f.worst_reach_excess;
    EXPECT_LE(f.fastest_tick_move, MoveConfig{}.max_speed + kTolerance / kDt) << map.name;
    // They do wander: most of the run is spent moving.
    EXPECT_GT(f.mean_travel, 0.25f * MoveConfig{}.max_speed * 60.0f) << map.name;
    EXPECT_GT(f.goals_reached, kBots) << map.name;
}

class OpenArenaWander : public ::testing::TestWithParam<const char*> {};

TEST_P(OpenArenaWander, TwoHundredBotsForSixtySeconds) {
    DSOC_REQUIRE_OPENARENA();
    const auto map = maps::load_map(GetParam(), maps::MapSearch{{testing::kOpenArenaPak}});
    ASSERT_TRUE(map.ok()) << map.error().message();
    check(map.value(), 1);
}

INSTANTIATE_TEST_SUITE_P(Maps, OpenArenaWander,
                         ::testing::Values("oa_dm4", "q3dm6ish", "ctf_inyard", "wrackdm17",
                                           "oa_ctf2", "suspended"));

TEST(GeneratedWander, TwoHundredBotsForSixtySeconds) {
    for (const char* spec : {"gen:city:3", "gen:rooms:3"}) {
        const auto map = maps::load_map(spec, maps::MapSearch{});
        ASSERT_TRUE(map.ok()) << map.error().message();
        check(map.value(), 2);
    }
}

} // namespace
} // namespace dsoc::sim

namespace dsoc::sim {
namespace {

TEST(GeneratedWander, DeterministicGivenTheSeed) {
    const auto map = maps::load_map("gen:rooms:5", maps::MapSearch{});
    ASSERT_TRUE(map.ok());
    const CollisionWorld world(map->collision_brushes);
    auto run = [&](std::uint64_t seed) {
        auto bots = spawn_wander_bots(world, MoveConfig{}, map->spawn_points, 20, seed);
        for (int tick = 0; tick < 300; ++tick) {
            for (WanderBot& bot : bots) {
                wander_step(bot, world, WanderConfig{}, MoveConfig{}, map->spawn_points,
                            map->hazards, kDt);
            }
        }
        std::vector<glm::vec3> out;
        for (const WanderBot& bot : bots) {
            out.push_back(bot.state.position);
        }
        return out;
    };
    EXPECT_EQ(run(9), run(9));
    EXPECT_NE(run(9), run(10));
}

TEST(GeneratedWander, HazardsRespawn) {
    // A floor covered by a hazard: the bot dies as soon as it lands.
    auto spec = maps::parse_text_map("dsoc-map 1\n"
                                     "box solid -512 -512 -16 512 512 0\n"
                                     "spawn 0 0 25\n"
                                     "hazard -512 -512 0 512 512 2\n", // the whole floor
                                     "pit");
    ASSERT_TRUE(spec.ok());
    const maps::Map map = maps::build_map(spec.value(), "pit");
    const CollisionWorld world(map.collision_brushes);
    auto bots = spawn_wander_bots(world, MoveConfig{}, map.spawn_points, 1, 1);
    for (int tick = 0; tick < 30; ++tick) {
        wander_step(bots[0], world, WanderConfig{}, MoveConfig{}, map.spawn_points, map.hazards,
                    kDt);
    }
    EXPECT_GT(bots[0].deaths, 0u);
}

} // namespace
} // namespace dsoc::sim
