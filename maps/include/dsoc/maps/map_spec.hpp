#pragma once
// A map described brush by brush, before geometry is computed: what our text format
// holds and what the generators produce. build_map() turns it into a Map.
//
// Text format ("dsoc-map 1"), one statement a line, '#' starts a comment:
//   dsoc-map 1                                  first statement, required
//   name <word>                                 optional
//   box <kind> minx miny minz maxx maxy maxz    an axis-aligned brush
//   brush <kind> <n>                            a convex brush of n planes (4..64),
//   plane nx ny nz d                            ... followed by n plane lines; solid
//                                               where dot(n, x) <= d, n need not be unit
//   spawn x y z [yaw [classname]]               a spawn point (player origin)
//   hazard minx miny minz maxx maxy maxz        a box that kills (a pit, lava)
// Kinds: solid (blocks sight and players), glass (blocks players, not sight),
// caulk (solid that draws nothing: blocks players, not sight), clip (player clip).
// Numbers are decimal; every coordinate must be finite with |value| <= 1e6.

#include "dsoc/maps/load_error.hpp"
#include "dsoc/maps/map.hpp"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::maps {

enum class BrushKind : std::uint8_t { solid, glass, caulk, clip };

/// "solid", "glass", "caulk", "clip". Static storage.
const char* to_string(BrushKind kind) noexcept;

struct BrushSpec {
    BrushKind kind = BrushKind::solid;
    std::vector<visibility::Plane> planes;

    static BrushSpec box(BrushKind kind, const visibility::Aabb& bounds);
};

struct MapSpec {
    std::string name = "unnamed";
    std::vector<BrushSpec> brushes;
    std::vector<SpawnPoint> spawn_points;
    std::vector<Hazard> hazards;
};

/// Largest brush accepted by the text format. [Units: planes]
inline constexpr std::size_t kMaxPlanesPerBrush = 64;
/// Largest coordinate accepted by the text format. [Units: world units]
inline constexpr float kMaxTextCoordinate = 1.0e6f;

/// Parses our text format. Errors name `file` and the line.
[[nodiscard]] Result<MapSpec> parse_text_map(std::string_view text, const std::string& file);
/// Reads and parses a text map file.
[[nodiscard]] Result<MapSpec> read_text_map_file(const std::filesystem::path& path);
/// Writes `spec` in the text format; parse_text_map() of the result gives the same
/// brushes (planes written with 9 significant digits) and spawn points.
[[nodiscard]] std::string format_text_map(const MapSpec& spec);

/// Computes the geometry: occluders from solid brushes, collision brushes from all,
/// degenerate brushes counted and skipped. `source` is recorded in Map::source.
[[nodiscard]] Map build_map(const MapSpec& spec, std::string source);

} // namespace dsoc::maps
