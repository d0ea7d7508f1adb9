#pragma once
// Exact from-region occlusion by one convex occluder ("strong occlusion"), the
// second stage behind the extended-projection z-pyramid.
//
// For a box of eyes R, a box B and a convex solid O: every segment from any point of
// R to any point of B passes through O's interior iff the 64 segments joining R's 8
// corners to B's 8 corners all do. (For a fixed end q, the set of p whose segment to
// q meets int O is convex; so is the set of q for a fixed p. A box is the convex hull
// of its corners.) The test is exact for one occluder at a time - it does not fuse
// occluders - but it does not lose the region's parallax at every texel the way an
// extended projection does, which on real maps with a 48-unit reach makes it cull
// several times more (docs/region-visibility.md).

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/cut_plane_fusion.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_grid.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>
#include <vector>

namespace dsoc::visibility {

/// True when every segment from a point of `region` to a point of `box` passes
/// through the interior of the convex solid { x : dot(n_i, x) <= d_i }.
[[nodiscard]] bool shaft_blocked_by(const Aabb& region, const Aabb& box,
                                    std::span<const Plane> planes);

/// The same for an axis-aligned solid box, in float: every segment passes through the
/// interior of `solid` shrunk by kBoxShrink on every side (the shrink absorbs float
/// rounding, so `true` also holds for the exact box). About 5x cheaper than the planes.
[[nodiscard]] bool shaft_blocked_by_box(const Aabb& region, const Aabb& box, const Aabb& solid);

/// True when the open segment a-b passes through the interior of `solid` shrunk by
/// kBoxShrink (positive length inside; float). `true` implies segment_blocked_by() for
/// the box's six planes.
[[nodiscard]] bool segment_through_box(glm::vec3 a, glm::vec3 b, const Aabb& solid);

/// How far the box fast path shrinks a solid box: float rounding at world coordinates
/// up to 2^15 units stays below it. [Units: world units]
inline constexpr float kBoxShrink = 1.0f / 64.0f;

/// Shaft stage over a world: `occluded` when some single occluder blocks every
/// segment from `region` to `box` (exact per occluder, see above) or, with fusion on,
/// when the occluders cut by one of a few axis-aligned planes through the walls the
/// centre segment crosses cover every crossing together (cut_plane_fusion.hpp);
/// `visible` otherwise (may be a false positive). Occluders that cut into the region
/// take part: the arguments need only convexity.
class ShaftOcclusion {
public:
    /// `world` and `grid` (built over `world`) must outlive this.
    explicit ShaftOcclusion(const OccluderWorld& world, const OccluderGrid& grid,
                            bool fusion = true)
        : world_(&world), grid_(&grid), fusion_(fusion) {}

    /// Per-thread memory, reused between tests.
    struct Scratch {
        OccluderGrid::Scratch grid;
        CutPlaneFusion::Scratch fusion;
        std::vector<CutPlane> planes;
    };

    /// `hint` (optional, in/out): 0, or 1 + the id of an occluder to try first (written
    /// here when a single occluder proves the box hidden; reset to 0 otherwise).
    [[nodiscard]] Visibility test(const Aabb& region, const Aabb& box, Scratch& scratch,
                                  std::uint32_t* hint = nullptr) const;

    /// Occluders given the full 64-segment test per query at most (those that block
    /// the centre-to-centre segment); past it no further single occluder is tried.
    static constexpr int kMaxFullTests = 16;
    /// Cut planes tried for fusion per query at most: the axis planes through the
    /// middle of the occluders that block the centre segment, nearest the region
    /// first. (On oa_dm4, 3 planes prove 98% of what 6 do at 60% of the cost.)
    static constexpr std::size_t kMaxCutPlanes = 3;

private:
    const OccluderWorld* world_;
    const OccluderGrid* grid_;
    bool fusion_;
};

} // namespace dsoc::visibility
