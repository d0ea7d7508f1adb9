#pragma once
// One entry point for "give me this map": a path to a .bsp or a text map, a map
// name looked up in .pk3 archives, or a generator. No global state: every function
// may be called from several threads at once.

#include "dsoc/maps/load_error.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/maps/q3_bsp.hpp"

#include <filesystem>
#include <string_view>
#include <vector>

namespace dsoc::maps {

/// Where OpenArena's Debian package puts its archives.
inline constexpr const char* kOpenArenaBaseDir = "/usr/share/games/openarena/baseoa";

/// Places to look for a map given by name: .pk3 files, or directories whose *.pk3
/// (and maps/<name>.bsp) are searched. Earlier locations win; inside a directory,
/// later-sorting archives win (as in Quake 3, where pak1 overrides pak0).
struct MapSearch {
    std::vector<std::filesystem::path> locations;

    /// The paths in $DSOC_MAP_PATH (':'-separated), then kOpenArenaBaseDir.
    [[nodiscard]] static MapSearch from_environment();
};

/// Loads a map from `spec`:
/// - an existing file: ".bsp" is read as Quake 3 BSP, a ".pk3" holding exactly one
///   map gives that map, anything else is read as our text map;
/// - "gen:city[:seed]" or "gen:rooms[:seed]": a generated world with default sizes;
/// - otherwise a map name, e.g. "oa_dm4", looked up as maps/<name>.bsp in `search`.
/// A name found nowhere is an error listing where it looked.
[[nodiscard]] Result<Map> load_map(std::string_view spec, const MapSearch& search);

/// The parsed BSP of a map given by name, found as load_map() finds it: for reading
/// the lumps a Map does not hold (the PVS, see q3_pvs.hpp).
[[nodiscard]] Result<q3::Q3Bsp> find_q3_bsp(std::string_view name, const MapSearch& search);

/// Names of all maps reachable through `search`, sorted, without duplicates.
[[nodiscard]] std::vector<std::string> list_maps(const MapSearch& search);

} // namespace dsoc::maps
