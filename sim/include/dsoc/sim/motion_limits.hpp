#pragma once
// The speed contract of walking movement (motion_bound()) in the interest manager's
// terms: what a TBV or a viewer's eye region may assume about a walking entity.

#include "dsoc/sim/player_move.hpp"
#include "dsoc/visibility/tbv.hpp"

namespace dsoc::sim {

/// Motion limits of an entity moved by player_move() under `move`: horizontal speed
/// max_speed; rise jump_velocity + climb_rate per second plus one step; fall at most
/// max_fall_speed, and under gravity from the current downward speed.
[[nodiscard]] inline visibility::MotionLimits walking_limits(const MoveConfig& move) {
    visibility::MotionLimits m;
    m.horizontal_speed = move.max_speed;
    m.up_speed = move.jump_velocity + move.climb_rate;
    m.down_speed = move.max_fall_speed;
    m.gravity = move.gravity;
    m.vertical_slack = move.step_height;
    return m;
}

} // namespace dsoc::sim
