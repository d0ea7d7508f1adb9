#pragma once
// Walking movement for bots and client avatars, after Quake 3's pmove: a box with
// gravity, friction and acceleration, swept against the collision brushes with
// sliding and step-up. Deterministic: same inputs, same results.
//
// Speed contract (what an interest manager may rely on; see motion_bound()):
// - horizontal speed never exceeds max_speed, so the horizontal distance covered in
//   t seconds is at most max_speed * t;
// - vertical velocity stays in [-max_fall_speed, jump_velocity], and the downward
//   speed grows by at most gravity * dt per move from the larger of where it was and,
//   standing on walkable ground, walk_down_speed() of that ground (0 on flat ground),
//   so in t seconds of moves of dt an entity falls at most
//   (max(v0, G) + gravity * dt / 2) * t + gravity * t^2 / 2, with G the largest
//   walk_down_speed of the ground it stands on meanwhile (at most walk_down_speed() of
//   the steepest walkable ground);
// - every way up (a jump, a ramp, a step onto a ledge) is paid from one climb credit
//   that refills at climb_rate (>= jump_velocity) and holds at most step_height, so
//   the rise in t seconds is at most step_height + climb_rate * t. A step the credit
//   cannot pay for is not taken (the ledge blocks, like a higher one, until the
//   credit has refilled): on stairs steeper than climb_rate / max_speed a player
//   climbs at climb_rate, not faster.

#include "dsoc/maps/map.hpp"
#include "dsoc/sim/collision_world.hpp"

#include <glm/vec3.hpp>

#include <span>
#include <string>
#include <vector>

namespace dsoc::sim {

struct MoveConfig {
    /// Horizontal speed limit. [Units: world units/s] [Limit: > 0]
    float max_speed = 320.0f;
    /// [Units: world units/s^2] [Limit: >= 0]
    float gravity = 800.0f;
    /// Upward speed a jump sets; also the upward velocity limit. [Units: world units/s]
    /// [Limit: >= 0, <= climb_rate]
    float jump_velocity = 270.0f;
    /// Terminal falling speed (Quake 3 has none; a bound needs one). [Units: world units/s] [Limit:
    /// > 0]
    float max_fall_speed = 1600.0f;
    /// Highest ledge walked onto without jumping. [Units: world units] [Limit: >= 0]
    float step_height = 18.0f;
    /// Sustained rise limit: the rate at which the climb credit refills, which pays for
    /// every rise (jumps, ramps, steps). [Units: world units/s] [Limit: >= jump_velocity]
    float climb_rate = 270.0f;
    /// Ground and air acceleration (Quake 3 pm_accelerate, pm_airaccelerate). [Units: 1/s] [Limit:
    /// >= 0]
    float ground_accelerate = 10.0f;
    float air_accelerate = 1.0f;
    /// Ground friction and the speed below which friction stops as if at this speed.
    /// [Units: 1/s, world units/s] [Limit: >= 0]
    float friction = 6.0f;
    float stop_speed = 100.0f;
    /// Ground steeper than this (normal.z below it) is a wall to slide down. [Limit: 0..1]
    float min_walk_normal_z = 0.7f;
    /// The player's box around its origin: Quake 3's 30x30x56 standing box.
    /// [Units: world units] [Limit: mins < maxs]
    glm::vec3 mins{-15.0f, -15.0f, -24.0f};
    glm::vec3 maxs{15.0f, 15.0f, 32.0f};
    /// Eye above the origin (Quake 3 DEFAULT_VIEWHEIGHT). [Units: world units]
    float eye_height = 26.0f;
};

/// Every problem with the settings, in words; empty when they are usable.
std::vector<std::string> validate(const MoveConfig& config);

struct MoveState {
    glm::vec3 position{0.0f}; ///< origin of the box [Units: world units]
    glm::vec3 velocity{0.0f}; ///< [Units: world units/s]
    bool on_ground = false;
    glm::vec3 ground_normal{0.0f, 0.0f, 1.0f}; ///< valid when on_ground
    float climb_credit = 0.0f;                 ///< [Units: world units] in [0, step_height]
};

struct MoveInput {
    /// Wanted horizontal direction: unit length or zero (z is ignored).
    glm::vec3 wish_direction{0.0f};
    bool jump = false;
};

/// How far an entity can get from where it is in `seconds`.
struct MotionBound {
    float horizontal = 0.0f; ///< in the xy plane [Units: world units]
    float up = 0.0f;         ///< [Units: world units]
    float down = 0.0f;       ///< [Units: world units]
};

/// The downward speed reachable without falling: max_speed down ground whose normal
/// has z component `normal_z` (default: the steepest walkable ground); 0 on flat ground.
/// [Units: world units/s]
[[nodiscard]] float walk_down_speed(const MoveConfig& config, float normal_z);
[[nodiscard]] inline float walk_down_speed(const MoveConfig& config) {
    return walk_down_speed(config, config.min_walk_normal_z);
}

/// Conservative reach in `seconds` (>= 0), for movement stepped with any tick length
/// (add one tick to `seconds` when it is not a whole number of ticks):
/// horizontal = max_speed * t; up = climb_rate * t + step_height;
/// down = max_fall_speed * t.
[[nodiscard]] MotionBound motion_bound(const MoveConfig& config, float seconds);

/// Advances `state` by `dt` seconds (0 < dt <= 0.1 recommended). Never moves the box
/// into a brush when it starts outside one (a trace that starts inside one stops).
void player_move(const CollisionWorld& world, const MoveConfig& config, const MoveInput& input,
                 float dt, MoveState& state);

/// Whether the box of a player at `state` touches one of `hazards` (a pit's
/// trigger_hurt, lava): such a player dies, and a simulation respawns it.
[[nodiscard]] bool touches_hazard(const MoveConfig& config, const MoveState& state,
                                  std::span<const maps::Hazard> hazards);

/// Puts a player at a spawn point's origin (raised a little, as Quake 3 does, so that
/// the box does not touch the floor) and finds the ground.
[[nodiscard]] MoveState spawn_state(const CollisionWorld& world, const MoveConfig& config,
                                    glm::vec3 spawn_origin);

} // namespace dsoc::sim
