#pragma once
// From a parsed Quake 3 BSP to a dsoc Map. The rules (see docs/maps.md):
// - Only the world (model 0) is used; doors and platforms (other models) move.
// - A brush blocks players when its content shader has CONTENTS_SOLID or
//   CONTENTS_PLAYERCLIP; those become collision brushes.
// - A brush blocks sight (an occluder) when it has CONTENTS_SOLID, not
//   CONTENTS_TRANSLUCENT (glass, grates), at least one side without SURF_NODRAW
//   (an all-caulk brush draws nothing, so nothing is hidden behind it), and no drawn
//   side whose shader lets sight through (q3_shaders.hpp: by the game's shader
//   scripts when given whole, else by what the shader's name suggests).
// - Curved patches are left out (counted in stats.patches_left_out): an occluder
//   left out only makes culling less tight, never wrong.
// - Hazards: trigger_hurt entities doing at least kLethalHurtDamage (bounds of their
//   brush model) and world brushes with CONTENTS_LAVA (their bounds).
// - Brushes whose planes make no bounded, non-empty polyhedron are skipped and
//   counted by reason.

#include "dsoc/maps/load_error.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/maps/q3_bsp.hpp"
#include "dsoc/maps/q3_shaders.hpp"

#include <filesystem>
#include <string>
#include <string_view>

namespace dsoc::maps {

/// A trigger_hurt doing at least this much damage a hit kills. [Units: hit points]
inline constexpr int kLethalHurtDamage = 100;

/// Builds a Map from a parsed BSP, telling see-through shaders by `scripts` (the game's
/// shader scripts; null: by name alone). Fails only on a malformed entity string.
[[nodiscard]] Result<Map> map_from_q3_bsp(const q3::Q3Bsp& bsp, std::string name,
                                          const ShaderScripts* scripts = nullptr);

/// Loads "maps/<name>.bsp" from a .pk3 archive.
[[nodiscard]] Result<Map> load_q3_map_from_pk3(const std::filesystem::path& pk3,
                                               std::string_view name,
                                               const ShaderScripts* scripts = nullptr);

/// Loads a plain .bsp file; the map is named after the file's stem.
[[nodiscard]] Result<Map> load_q3_map_from_bsp(const std::filesystem::path& bsp_file,
                                               const ShaderScripts* scripts = nullptr);

} // namespace dsoc::maps
