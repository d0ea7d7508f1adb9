#pragma once
// The speed contract of walking movement (motion_bound()) in the interest manager's
// terms: what a TBV or a viewer's eye region may assume about a walking entity.

#include "dsoc/sim/player_move.hpp"
#include "dsoc/visibility/tbv.hpp"

namespace dsoc::sim {

/// Motion limits of an entity moved by player_move() under `move` in ticks of
/// `tick_seconds`: horizontal speed max_speed; rise climb_rate per second plus one
/// step (the climb credit); fall at most max_fall_speed, and under gravity from the
/// larger of the current downward speed and walk_down_speed(), plus the tick's
/// discretisation (player_move.hpp states the contract).
[[nodiscard]] inline visibility::MotionLimits walking_limits(const MoveConfig& move,
                                                             float tick_seconds) {
    visibility::MotionLimits m;
    m.horizontal_speed = move.max_speed;
    m.up_speed = move.climb_rate;
    m.down_speed = move.max_fall_speed;
    m.gravity = move.gravity;
    m.fall_speed_floor = walk_down_speed(move);
    m.fall_speed_margin = move.gravity * tick_seconds * 0.5f;
    m.vertical_slack = move.step_height; // one step up, paid from the climb credit
    // Below: the fall law needs no step (the mover never steps down); a quarter unit
    // for float rounding of positions far from the origin.
    m.fall_slack = 0.25f;
    return m;
}

} // namespace dsoc::sim
