#pragma once
// A loaded map, whatever it came from (Quake 3 BSP, our text format, a generator):
// what blocks sight, what blocks movement, and where players start.

#include "dsoc/maps/curved_surface.hpp"
#include "dsoc/maps/load_error.hpp"
#include "dsoc/maps/pvs.hpp"
#include "dsoc/visibility/convex_polyhedron.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace dsoc::maps {

/// What a brush is made of (a subset of Quake 3 content flags, same bit values).
enum BrushContents : std::uint32_t {
    contents_solid = 0x1,              ///< blocks players (and shots)
    contents_player_clip = 0x10000,    ///< invisible wall that blocks players only
    contents_translucent = 0x20000000, ///< glass, grates: blocks players, not sight
};

/// A convex brush for movement: the half-spaces dot(n, x) <= d of its sides, with
/// axial bevel planes (normals +-X, +-Y, +-Z at the bounds) always present so that
/// the "expand each plane by the box's support distance" swept-box trace is exact on
/// axial faces and conservative (never lets a box through) near other edges.
struct CollisionBrush {
    std::vector<visibility::Plane> planes;
    visibility::Aabb bounds;
    std::uint32_t contents = contents_solid;
};

/// A volume that kills a player who touches it (a bottomless pit's trigger_hurt,
/// lava). Simulations respawn a player whose box overlaps one.
struct Hazard {
    visibility::Aabb bounds;
    std::string reason; ///< e.g. "trigger_hurt dmg 9999", "lava"
};

struct SpawnPoint {
    glm::vec3 origin{0.0f}; ///< where a player's origin is put [Units: world units]
    float yaw_degrees = 0.0f;
    std::string classname; ///< e.g. "info_player_deathmatch", "team_CTF_redspawn"
};

/// Brushes whose planes did not make a usable convex polyhedron, by reason
/// (dsoc::visibility::PolyhedronError). Such brushes are left out of both the
/// occluders and the collision brushes.
struct DegenerateCounts {
    std::size_t too_many_planes =
        0; ///< more than kMaxBrushPlanes sides (bounds the work per brush)
    std::size_t too_few_planes = 0;
    std::size_t non_finite_plane = 0;
    std::size_t unbounded = 0;
    std::size_t empty = 0;
    [[nodiscard]] std::size_t total() const {
        return too_many_planes + too_few_planes + non_finite_plane + unbounded + empty;
    }
};

struct MapStats {
    std::size_t brushes_total = 0;        ///< every brush in the file (all models)
    std::size_t world_brushes = 0;        ///< brushes of the world (model 0)
    std::size_t opaque_candidates = 0;    ///< world brushes passing the occluder content rules
    std::size_t opaque_occluders = 0;     ///< of those, with usable geometry (= occluders.size())
    std::size_t collision_candidates = 0; ///< world brushes that block players
    std::size_t collision_brushes = 0;    ///< of those, with usable geometry
    std::size_t translucent_skipped = 0; ///< solid but translucent (glass): collide, do not occlude
    std::size_t nodraw_skipped = 0; ///< solid, every side nodraw (caulk): collide, do not occlude
    std::size_t see_through_skipped =
        0; ///< solid, drawn with a shader that lets sight
           ///< through (grate, fence, window...): collide, do not occlude
    /// Shader scripts that told see-through shaders apart (0: none read whole, so a
    /// shader's name did: q3_shaders.hpp).
    std::size_t shader_scripts = 0;
    std::size_t patches_left_out = 0; ///< curved patch surfaces not turned into occluders
    std::size_t opaque_patches = 0;   ///< of those, the world's drawn opaque (= opaque_patches)
    DegenerateCounts degenerate;      ///< collision candidates with unusable geometry
};

struct Map {
    std::string name;
    std::string source; ///< file (or "pk3:entry") it came from; "generator:..." for generated maps
    /// Brushes that block sight: the convex solids an occluder culler may trust.
    std::vector<visibility::ConvexPolyhedron> occluders;
    /// Brushes that block player movement (a superset of the occluders' volumes:
    /// also glass, caulk and player clip).
    std::vector<CollisionBrush> collision_brushes;
    std::vector<SpawnPoint> spawn_points;
    std::vector<Hazard> hazards;
    /// The bounds of the solid brushes that let sight through (stats.see_through_skipped:
    /// grates, windows), which the compiler's vis took for walls (the PVS is opened
    /// through them: pvs.hpp).
    std::vector<visibility::Aabb> see_through;
    /// The world's curved surfaces that the game draws opaque (Quake 3 maps): not
    /// occluders (a culler may not trust what it does not use), but they block sight,
    /// so the evaluation's ray oracle takes them (curved_surface.hpp).
    std::vector<CurvedSurface> opaque_patches;
    /// Union of the collision brushes' bounds (empty when there are none).
    visibility::Aabb bounds;
    MapStats stats;
    /// The compiler's potentially visible set, for Quake 3 maps (null for text and
    /// generated maps).
    std::shared_ptr<const Pvs> pvs;
    /// Shader scripts of the game that could not be read whole (q3_shaders.hpp): where
    /// they do not answer, a shader's name tells whether it lets sight through.
    std::vector<LoadError> shader_script_problems;
};

/// Adds the axial bevel planes a CollisionBrush needs (those of `bounds` whose
/// normal is not already among `planes`). Used by every loader.
void add_axial_bevels(std::vector<visibility::Plane>& planes, const visibility::Aabb& bounds);

/// Most sides a brush may have (Quake 3's compiler allows 300 while building; the 50
/// OpenArena maps have at most 65). More is skipped as degenerate. [Units: planes]
inline constexpr std::size_t kMaxBrushPlanes = 256;

/// Tolerance used when turning brush planes into polyhedra. [Units: world units]
inline constexpr float kBrushTolerance = 1.0f / 64.0f;

} // namespace dsoc::maps
