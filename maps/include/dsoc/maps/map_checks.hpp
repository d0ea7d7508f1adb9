#pragma once
// Sanity checks on a loaded map: contents that load without an error but make no
// sense for a game server (nothing to occlude, spawn points outside the world or
// inside walls, non-finite geometry, coordinates no Quake 3 map can have). A map that
// parses is not necessarily one a server should run: these findings say why not.

#include "dsoc/maps/map.hpp"

#include <string>
#include <vector>

namespace dsoc::maps {

enum class FindingSeverity : std::uint8_t {
    warning,  ///< the map works, but something about it is absurd or degrades culling
    unusable, ///< no server should run it (no player could spawn, or geometry is not finite)
};

/// "warning" or "unusable". Static storage.
const char* to_string(FindingSeverity severity) noexcept;

struct MapFinding {
    FindingSeverity severity = FindingSeverity::warning;
    std::string code; ///< stable identifier, e.g. "no_occluders", "spawn_in_solid"
    std::string text; ///< what is wrong and what it means, with counts and examples
};

/// Largest coordinate a Quake 3 map can have (its MAX_WORLD_COORD); geometry beyond
/// it means a map scaled absurdly. [Units: world units]
inline constexpr float kMaxWorldCoordinate = 131072.0f;

/// How deep inside a brush a spawn point must be to count as inside solid, so that
/// one resting on a face is not. [Units: world units]
inline constexpr float kSpawnInSolidDepth = 1.0f;

/// How far above the highest collision brush a spawn point may be and still count as
/// inside the world (a roofless map's spawns stand above its walls). [Units: world units]
inline constexpr float kSpawnHeadroom = 256.0f;

/// Every finding about `map`, warnings and unusable alike, in a fixed order (codes:
/// non_finite_geometry, no_spawn_points, no_usable_spawn_point, spawn_outside_world,
/// spawn_in_solid, spawn_in_hazard, no_occluders, no_collision_brushes,
/// beyond_world_limit, degenerate_brushes, shader_scripts_unread). Empty for a sound map. Pure: may
/// be called from several threads at once.
[[nodiscard]] std::vector<MapFinding> check_map(const Map& map);

/// True when some finding is FindingSeverity::unusable.
[[nodiscard]] bool any_unusable(const std::vector<MapFinding>& findings);

} // namespace dsoc::maps
