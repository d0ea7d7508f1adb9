#pragma once
// Quake 3 BSP (IBSP version 46) parsed into validated, typed lumps.
//
// parse_q3_bsp() checks everything a later reader would trust: magic and version,
// every lump's offset and length against the file size, that lengths divide by the
// record size, and that every index (brush -> sides, side -> plane and shader,
// model -> brushes, node -> plane and children, leaf -> leaf brushes, leaf brush ->
// brush, cluster -> visibility rows) is in range. After a successful parse, any
// index read from a Q3Bsp is valid without further checks. Floats are not checked
// here (the geometry step reports non-finite planes as degenerate brushes).
//
// The raw file bytes are kept (raw_lump()) so that lumps not decoded here (draw
// surfaces, vertexes, lightmaps) can be read later without re-opening the file.

#include "dsoc/maps/load_error.hpp"

#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::maps::q3 {

inline constexpr int kBspVersion = 46;
inline constexpr int kLumpCount = 17;

enum class Lump : int {
    entities = 0,
    shaders = 1,
    planes = 2,
    nodes = 3,
    leafs = 4,
    leaf_surfaces = 5,
    leaf_brushes = 6,
    models = 7,
    brushes = 8,
    brush_sides = 9,
    draw_verts = 10,
    draw_indexes = 11,
    fogs = 12,
    surfaces = 13,
    lightmaps = 14,
    light_grid = 15,
    visibility = 16,
};

/// "brushes (lump 8)" etc. Static storage.
const char* lump_label(Lump lump) noexcept;

/// Quake 3 content flags (shader `contentFlags`) and surface flags used here.
inline constexpr std::uint32_t kContentsSolid = 0x1;
inline constexpr std::uint32_t kContentsLava = 0x8;
inline constexpr std::uint32_t kContentsSlime = 0x10;
inline constexpr std::uint32_t kContentsWater = 0x20;
inline constexpr std::uint32_t kContentsFog = 0x40;
inline constexpr std::uint32_t kContentsPlayerClip = 0x10000;
inline constexpr std::uint32_t kContentsMonsterClip = 0x20000;
inline constexpr std::uint32_t kContentsTranslucent = 0x20000000;
inline constexpr std::uint32_t kSurfNoDraw = 0x80;
inline constexpr std::uint32_t kSurfSky = 0x4;

struct Shader {
    std::string name; ///< up to 63 characters, NUL-terminated in the file
    std::uint32_t surface_flags = 0;
    std::uint32_t content_flags = 0;
};

/// Brush side planes point out of the brush: solid where dot(normal, x) <= dist.
struct Plane {
    glm::vec3 normal{0.0f};
    float dist = 0.0f;
};

/// Children: >= 0 is a node index, < 0 is leaf index -(child + 1).
struct Node {
    std::int32_t plane = 0;
    std::array<std::int32_t, 2> children{};
    std::array<std::int32_t, 3> mins{};
    std::array<std::int32_t, 3> maxs{};
};

struct Leaf {
    std::int32_t cluster = -1; ///< -1: outside the map / opaque
    std::int32_t area = -1;
    std::array<std::int32_t, 3> mins{};
    std::array<std::int32_t, 3> maxs{};
    std::int32_t first_leaf_surface = 0;
    std::int32_t num_leaf_surfaces = 0;
    std::int32_t first_leaf_brush = 0;
    std::int32_t num_leaf_brushes = 0;
};

struct Model {
    glm::vec3 mins{0.0f};
    glm::vec3 maxs{0.0f};
    std::int32_t first_surface = 0;
    std::int32_t num_surfaces = 0;
    std::int32_t first_brush = 0;
    std::int32_t num_brushes = 0;
};

struct Brush {
    std::int32_t first_side = 0;
    std::int32_t num_sides = 0;
    std::int32_t shader = 0; ///< the brush's content shader
};

struct BrushSide {
    std::int32_t plane = 0;
    std::int32_t shader = 0;
};

/// A curved surface (surface type 2): a width x height grid of control points, read as
/// biquadratic Bezier patches of 3 x 3 points sharing their edges (both sizes odd,
/// from 3 to kMaxPatchSide; each patch has its own vertices, so all patches together
/// hold at most the draw vertices lump's). Points are as in the file (possibly not
/// finite).
struct Patch {
    std::int32_t surface = 0; ///< its index in the surfaces lump (models own ranges of it)
    std::int32_t shader = 0;
    std::int32_t width = 0;
    std::int32_t height = 0;
    std::vector<glm::vec3> points; ///< row by row: points[row * width + column]
};

/// Most control points along a side of a patch: the game refuses a patch of more than
/// MAX_PATCH_SIZE (32) a side, and sides are odd.
inline constexpr std::int32_t kMaxPatchSide = 31;

/// Cluster-to-cluster potentially visible set. Empty (num_clusters == 0) when the
/// map was compiled without vis (e.g. oa_ctf2): then everything is potentially visible.
struct Visibility {
    std::int32_t num_clusters = 0;
    std::int32_t bytes_per_cluster = 0;
    std::vector<std::uint8_t> bits; ///< num_clusters * bytes_per_cluster bytes
};

struct LumpInfo {
    std::uint32_t offset = 0;
    std::uint32_t length = 0;
};

struct Q3Bsp {
    std::string file; ///< for error messages
    std::vector<std::byte> bytes;
    std::array<LumpInfo, kLumpCount> lumps{};

    std::string entities; ///< entity text, trailing NULs removed
    std::vector<Shader> shaders;
    std::vector<Plane> planes;
    std::vector<Node> nodes;
    std::vector<Leaf> leafs;
    std::vector<std::int32_t> leaf_brushes;
    std::vector<Model> models;
    std::vector<Brush> brushes;
    std::vector<BrushSide> brush_sides;
    std::uint32_t surface_count = 0;       ///< records in the surfaces lump
    std::uint32_t patch_surface_count = 0; ///< of which curved patches (type 2)
    std::vector<Patch> patches;            ///< those patches, decoded
    std::uint32_t leaf_surface_count = 0;
    Visibility visibility;

    /// The bytes of a lump; always within `bytes` (validated at parse time).
    [[nodiscard]] std::span<const std::byte> raw_lump(Lump lump) const;
    /// The sides of a brush (validated range).
    [[nodiscard]] std::span<const BrushSide> sides_of(const Brush& brush) const;
};

/// Parses a whole .bsp file held in memory. `file` names it in errors. Never throws
/// for bad input; allocation is bounded by the input size.
[[nodiscard]] Result<Q3Bsp> parse_q3_bsp(std::span<const std::byte> bytes, std::string file);

/// Reads and parses a plain .bsp file.
[[nodiscard]] Result<Q3Bsp> read_q3_bsp_file(const std::filesystem::path& path);

} // namespace dsoc::maps::q3
