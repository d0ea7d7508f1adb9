#pragma once
// Shots that hit: the deathmatch rule that keeps a world's population spread over its
// map as a real match's is. A shot is hitscan, as Quake 3's machinegun and railgun:
// a segment from the shooter's eye along its view, stopped by the first solid brush
// (not by player clips, which block only movement, as in Quake 3's shot mask), that hits
// the nearest other living entity's box on it. Each hit takes `damage` of an
// entity's kMaxHealth; at none left it dies and respawns at a spawn point (respawn.hpp).
//
// Without deaths, walkers that step off ledges they cannot climb gather on a map's
// lowest floor over minutes, until every client sees nearly every entity: a load no
// match has. With them, a player lives for seconds to a minute and starts again at a
// spawn point.

#include "dsoc/sim/collision_world.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace dsoc::sim {

/// An entity's health when it (re)spawns. [Units: health points]
inline constexpr int kMaxHealth = 100;

struct ShotSettings {
    /// Health a hit takes (0: shots are harmless; kMaxHealth or more: one hit kills).
    /// [Units: health points] [Limit: 0..kMaxHealth]
    int damage = 10;
    /// How far a shot reaches. [Units: world units] [Limit: > 0]
    float range = 8192.0f;
};

/// The unit vector a view with `yaw_deg` (about +z, from +x) and `pitch_deg` (Quake's
/// sign: positive looks down) points along.
[[nodiscard]] glm::vec3 view_direction(float yaw_deg, float pitch_deg);

/// Which of `boxes` a shot from `eye` along the unit vector `direction` hits: the one
/// whose box the segment enters first, among those with `hittable[i]` set and
/// i != `shooter`, before `range` and before the first brush of `world` (the brushes
/// that stop shots: solid ones); nothing when it hits none. `hittable` has
/// boxes.size() entries.
[[nodiscard]] std::optional<std::size_t> first_hit(const CollisionWorld& world, glm::vec3 eye,
                                                   glm::vec3 direction, float range,
                                                   std::span<const visibility::Aabb> boxes,
                                                   std::span<const std::uint8_t> hittable,
                                                   std::size_t shooter);

} // namespace dsoc::sim
