// Movement on small hand-made worlds: falling, landing, walls, sliding, steps, jumps,
// and the speed contract.

#include "dsoc/maps/map_spec.hpp"
#include "dsoc/sim/motion_limits.hpp"
#include "dsoc/sim/player_move.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace dsoc::sim {
namespace {

constexpr float kDt = 1.0f / 30.0f;

/// A 2048-wide walled floor at z = 0 with a wall at x = 512, a 16-high step and a
/// 24-high ledge further along y, and a 40-high crate.
maps::Map test_world() {
    const auto spec = maps::parse_text_map(R"(dsoc-map 1
box solid -1024 -1024 -64 1024 1024 0
box solid 512 -1024 0 576 1024 256
box solid -1024 300 0 -600 400 16
box solid -1024 600 0 -600 700 24
box solid 200 -400 0 264 -336 40
box solid -1088 -1088 0 -1024 1088 256
box solid 1024 -1088 0 1088 1088 256
box solid -1024 -1088 0 1024 -1024 256
box solid -1024 1024 0 1024 1088 256
spawn 0 0 25
)",
                                           "test");
    EXPECT_TRUE(spec.ok());
    return maps::build_map(spec.value(), "test");
}

float horizontal_speed(const MoveState& s) {
    return std::hypot(s.velocity.x, s.velocity.y);
}

/// A player with the default MoveConfig on test_world().
class PlayerMoveOnTestWorld : public ::testing::Test {
protected:
    const maps::Map map = test_world();
    const CollisionWorld world{map.collision_brushes};
    const MoveConfig config;
};

TEST_F(PlayerMoveOnTestWorld, FallsAndLandsOnTheFloor) {
    MoveState state;
    state.position = {0, 0, 200};
    for (int i = 0; i < 90; ++i) {
        player_move(world, config, {}, kDt, state);
    }
    EXPECT_TRUE(state.on_ground);
    EXPECT_NEAR(state.position.z, 24.0f, 0.2f); // origin 24 above the floor (mins.z = -24)
    EXPECT_GE(state.position.z, 24.0f);
    EXPECT_EQ(state.velocity.z, 0.0f);
}

TEST(PlayerMove, FallingSpeedIsCapped) {
    const CollisionWorld world; // nothing to land on
    MoveConfig config;
    config.max_fall_speed = 500.0f;
    MoveState state;
    for (int i = 0; i < 300; ++i) {
        player_move(world, config, {}, kDt, state);
        EXPECT_GE(state.velocity.z, -500.0f);
    }
    EXPECT_FLOAT_EQ(state.velocity.z, -500.0f);
}

TEST_F(PlayerMoveOnTestWorld, WalksAtMaxSpeedAndStopsAtWalls) {
    MoveState state = spawn_state(world, config, {0, 0, 25});
    MoveInput input;
    input.wish_direction = {1, 0, 0};
    float fastest = 0.0f;
    for (int i = 0; i < 150; ++i) {
        player_move(world, config, input, kDt, state);
        fastest = std::max(fastest, horizontal_speed(state));
        EXPECT_LE(horizontal_speed(state), config.max_speed + 1e-3f);
    }
    EXPECT_GT(fastest, 300.0f);
    // Against the wall at x = 512: the box's +x face (origin + 15) stays in front of it.
    EXPECT_LE(state.position.x + 15.0f, 512.0f);
    EXPECT_GT(state.position.x + 15.0f, 511.0f);
    EXPECT_NEAR(state.position.y, 0.0f, 1e-3f);
}

TEST_F(PlayerMoveOnTestWorld, SlidesAlongWalls) {
    MoveState state = spawn_state(world, config, {480, 0, 25});
    MoveInput input;
    input.wish_direction = glm::normalize(glm::vec3(1, -1, 0));
    for (int i = 0; i < 30; ++i) {
        player_move(world, config, input, kDt, state);
    }
    EXPECT_LE(state.position.x + 15.0f, 512.0f);
    EXPECT_LT(state.position.y, -100.0f); // kept moving along the wall
}

TEST_F(PlayerMoveOnTestWorld, StepsUpSmallLedgesOnly) {
    MoveInput input;
    input.wish_direction = {0, 1, 0};
    MoveState low = spawn_state(world, config, {-800, 200, 25});
    for (int i = 0; i < 20; ++i) {
        player_move(world, config, input, kDt, low);
    }
    EXPECT_GT(low.position.y, 300.0f);
    EXPECT_NEAR(low.position.z, 16.0f + 24.0f, 0.5f); // on top of the 16-high step

    MoveState high = spawn_state(world, config, {-800, 500, 25});
    for (int i = 0; i < 20; ++i) {
        player_move(world, config, input, kDt, high);
    }
    EXPECT_LT(high.position.y, 600.0f - 15.0f + 0.01f); // blocked by the 24-high ledge
    EXPECT_NEAR(high.position.z, 24.0f, 0.5f);
}

TEST_F(PlayerMoveOnTestWorld, JumpsOntoACrate) {
    MoveState state = spawn_state(world, config, {232, -500, 25});
    for (int i = 0; i < 30; ++i) {
        player_move(world, config, {}, kDt, state); // settle
    }
    MoveInput input;
    input.wish_direction = {0, 1, 0};
    // Run up, jump a little before the crate's face (y = -400).
    float peak = 0.0f;
    bool jumped = false;
    for (int i = 0; i < 60; ++i) {
        input.jump = !jumped && state.position.y > -470.0f;
        jumped = jumped || input.jump;
        if (state.on_ground && state.position.z > 50.0f) {
            input.wish_direction = glm::vec3(0.0f); // on top: stop there
        }
        player_move(world, config, input, kDt, state);
        peak = std::max(peak, state.position.z);
        EXPECT_LE(state.velocity.z, config.jump_velocity);
    }
    EXPECT_TRUE(jumped);
    EXPECT_NEAR(state.position.z, 40.0f + 24.0f, 0.5f) << "did not land on the crate";
    // Jump apex: v^2 / 2g = 45.6 units above the floor (less a tick's discretisation).
    EXPECT_GT(peak, 24.0f + 40.0f);
    EXPECT_LT(peak, 24.0f + 46.0f + 18.0f);
}

TEST_F(PlayerMoveOnTestWorld, MotionBoundHoldsForRandomInput) {
    MoveState state = spawn_state(world, config, {0, 0, 25});
    std::uint32_t rng = 12345;
    auto random = [&] {
        rng = rng * 1664525u + 1013904223u;
        return static_cast<float>(rng >> 8) / 16777216.0f;
    };
    MoveInput input;
    for (int i = 0; i < 3000; ++i) {
        if (i % 15 == 0) {
            const float angle = random() * 6.2831853f;
            input.wish_direction = {std::cos(angle), std::sin(angle), 0};
        }
        input.jump = random() < 0.05f;
        const glm::vec3 before = state.position;
        player_move(world, config, input, kDt, state);
        const glm::vec3 moved = state.position - before;
        const MotionBound bound = motion_bound(config, kDt);
        // Tolerance: float rounding of positions a few thousand units from the origin.
        EXPECT_LE(std::hypot(moved.x, moved.y), bound.horizontal + 0.01f);
        EXPECT_LE(moved.z, bound.up + 0.01f);
        EXPECT_GE(moved.z, -bound.down - 0.01f);
        EXPECT_FALSE(world.box_in_solid(state.position, config.mins, config.maxs));
    }
}

/// A walkable ramp (normal z 0.74) rising 180 units along +x, then sixteen steps 16
/// high and 12 deep (53 degrees: 427 u/s of rise at full speed, were it allowed).
maps::Map ramp_then_stairs_world() {
    std::string text = R"(dsoc-map 1
box solid -1024 -1024 -64 1024 1024 0
brush solid 5
plane 0 0 -1 0
plane -0.9 0 1 0
plane 1 0 0 200
plane 0 1 0 100
plane 0 -1 0 100
box solid 200 -100 0 1000 100 180
)";
    for (int k = 1; k <= 16; ++k) {
        text += "box solid " + std::to_string(200 + 12 * k) + " -100 180 1000 100 " +
                std::to_string(180 + 16 * k) + "\n";
    }
    text += "spawn -200 0 25\n";
    const auto spec = maps::parse_text_map(text, "ramp_then_stairs");
    EXPECT_TRUE(spec.ok());
    return maps::build_map(spec.value(), "ramp_then_stairs");
}

TEST(PlayerMove, EveryWayUpIsPaidFromOneClimbCredit) {
    const maps::Map map = ramp_then_stairs_world();
    const CollisionWorld world(map.collision_brushes);
    const MoveConfig config;
    for (const float dt : {1.0f / 30.0f, 1.0f / 20.0f, 1.0f / 10.0f}) {
        MoveState state = spawn_state(world, config, {-200, 0, 25});
        MoveInput input;
        input.wish_direction = {1, 0, 0};
        std::vector<float> heights{state.position.z};
        const int ticks = static_cast<int>(4.0f / dt);
        for (int i = 0; i < ticks; ++i) {
            input.jump = i % 7 == 3 && i < ticks / 2; // jumps on the ramp and stairs too
            player_move(world, config, input, dt, state);
            heights.push_back(state.position.z);
            ASSERT_GE(state.climb_credit, 0.0f);
            ASSERT_LE(state.climb_credit, config.step_height);
        }
        // Climbed the whole way: ramp (180) and sixteen steps (256), origin 24 above.
        EXPECT_NEAR(state.position.z, 180.0f + 256.0f + 24.0f, 0.5f) << "dt " << dt;
        // Over every run of moves, the rise stays within the climb bound.
        float worst_excess = -1e9f;
        for (std::size_t from = 0; from < heights.size(); ++from) {
            for (std::size_t to = from + 1; to < heights.size(); ++to) {
                const float seconds = static_cast<float>(to - from) * dt;
                worst_excess = std::max(worst_excess, heights[to] - heights[from] -
                                                          motion_bound(config, seconds).up);
            }
        }
        EXPECT_LE(worst_excess, 0.01f) << "dt " << dt;
    }
}

/// The largest amount by which `heights` (one per tick of `dt`, with the downward
/// speed at each) falls faster over some run of ticks than walking_limits() allows.
float worst_fall_excess(const std::vector<glm::vec2>& height_and_down_speed,
                        const MoveConfig& config, float dt) {
    const visibility::MotionLimits limits = walking_limits(config, dt);
    float worst = -1e9f;
    for (std::size_t from = 0; from < height_and_down_speed.size(); ++from) {
        const glm::vec2 start = height_and_down_speed[from];
        for (std::size_t to = from + 1; to < height_and_down_speed.size(); ++to) {
            const float seconds = static_cast<float>(to - from) * dt;
            const visibility::Aabb reach = visibility::reachable_box(
                visibility::Aabb{glm::vec3(0, 0, start.x), glm::vec3(0, 0, start.x)}, limits,
                seconds, 1.0f, start.y);
            worst = std::max(worst, reach.min.z - height_and_down_speed[to].x);
        }
    }
    return worst;
}

TEST(PlayerMove, FallsWithinTheGravityBoundDownRampsAndStairsAtAnyTickLength) {
    const maps::Map map = ramp_then_stairs_world();
    const CollisionWorld world(map.collision_brushes);
    const MoveConfig config;
    for (const float dt : {1.0f / 30.0f, 1.0f / 10.0f}) {
        // Down the stairs and the ramp from the top (a run the gravity law alone,
        // with the downward speed at rest, does not bound).
        MoveState walker = spawn_state(world, config, {420, 0, 460});
        MoveInput input;
        input.wish_direction = {-1, 0, 0};
        std::vector<glm::vec2> walk{{walker.position.z, 0.0f}};
        for (int i = 0; i < static_cast<int>(2.5f / dt); ++i) {
            player_move(world, config, input, dt, walker);
            walk.emplace_back(walker.position.z, std::max(0.0f, -walker.velocity.z));
        }
        EXPECT_NEAR(walker.position.z, 24.0f, 0.5f) << "dt " << dt << ": did not get down";
        EXPECT_LE(worst_fall_excess(walk, config, dt), 0.01f) << "dt " << dt;
        // A long drop: the tick's discretisation adds up.
        const CollisionWorld nothing;
        MoveState faller;
        faller.position = {0, 0, 5000};
        std::vector<glm::vec2> drop{{faller.position.z, 0.0f}};
        for (int i = 0; i < static_cast<int>(2.0f / dt); ++i) {
            player_move(nothing, config, {}, dt, faller);
            drop.emplace_back(faller.position.z, std::max(0.0f, -faller.velocity.z));
        }
        EXPECT_LE(worst_fall_excess(drop, config, dt), 0.01f) << "dt " << dt;
    }
}

TEST(PlayerMove, ValidateNamesBadFields) {
    MoveConfig config;
    EXPECT_TRUE(validate(config).empty());
    config.max_speed = 0.0f;
    config.mins = {20, 0, 0};
    EXPECT_EQ(validate(config).size(), 2u);
    MoveConfig slow_climb;
    slow_climb.climb_rate = slow_climb.jump_velocity - 1.0f; // a jump could not be paid for
    ASSERT_EQ(validate(slow_climb).size(), 1u);
    EXPECT_NE(validate(slow_climb)[0].find("climb_rate"), std::string::npos);
}

TEST(PlayerMove, MotionBoundFormula) {
    const MoveConfig config;
    const MotionBound b = motion_bound(config, 0.5f);
    EXPECT_FLOAT_EQ(b.horizontal, 160.0f);
    EXPECT_FLOAT_EQ(b.up, config.climb_rate * 0.5f + 18.0f);
    EXPECT_FLOAT_EQ(b.down, 800.0f);
}

} // namespace
} // namespace dsoc::sim
