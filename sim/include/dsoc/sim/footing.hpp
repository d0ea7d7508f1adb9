#pragma once
// Where a walker has footing, by the collision brushes: the ledges it should not walk
// off (a step ahead with no floor within a safe drop below it, as over the void under a
// space map or a bottomless pit, or a drop into a hazard), and the spawn points it can
// stand at.
// Quake 3's bots keep off them through their area graph (a walk off a ledge is a
// travel type only where the landing is safe); a bot without path finding needs the
// same rule from the collision brushes, or on an open map it spends much of its time
// falling through the void to the trigger_hurt at the bottom.
//
// Threading: reads the world only; safe to call concurrently.

#include "dsoc/maps/map.hpp"
#include "dsoc/sim/collision_world.hpp"
#include "dsoc/sim/player_move.hpp"

#include <glm/vec3.hpp>

#include <span>
#include <vector>

namespace dsoc::sim {

/// Whether the walker's box at `position`, moved up to `lookahead` units along
/// `direction` (horizontal, unit length; probed every half box width of the way), would
/// stand over nothing for more than `max_drop` units below, or fall from there into one
/// of `hazards` (touched anywhere between the step and the floor), or, carried on at
/// `speed` (horizontal, world units/s) while it falls to a floor more than a step below,
/// come down where that holds (a narrow ledge below is overshot). The way stops at a
/// wall or a step higher than step_height (movement deals with those). [Units: world
/// units]
[[nodiscard]] bool unsafe_ledge_ahead(const CollisionWorld& world, const MoveConfig& move,
                                      glm::vec3 position, glm::vec3 direction, float speed,
                                      float lookahead, float max_drop,
                                      std::span<const maps::Hazard> hazards);

/// The spawn points where a walker put there (spawn_state()) lands on a floor within
/// `max_drop` without touching a hazard, in their order; all of `spawns` when none does.
/// A map can have a spawn point over what the brushes leave open (curved patch floors
/// do not collide here): a player spawned there falls until it dies.
[[nodiscard]] std::vector<maps::SpawnPoint>
spawn_points_with_footing(const CollisionWorld& world, const MoveConfig& move,
                          std::span<const maps::SpawnPoint> spawns, float max_drop,
                          std::span<const maps::Hazard> hazards);

} // namespace dsoc::sim
