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

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace dsoc::visibility {

class OccluderBvh;

/// True when every segment from a point of `region` to a point of `box` passes
/// through the interior of the convex solid { x : dot(n_i, x) <= d_i }: the 64 corner
/// segments each pass segment_blocked_by(). With SSE2, two segments at a time; the
/// answers are shaft_blocked_by_scalar()'s.
[[nodiscard]] bool shaft_blocked_by(const Aabb& region, const Aabb& box,
                                    std::span<const Plane> planes);

/// shaft_blocked_by() one segment at a time: the path without SSE2, and the twin the
/// vector path is tested and timed against.
[[nodiscard]] bool shaft_blocked_by_scalar(const Aabb& region, const Aabb& box,
                                           std::span<const Plane> planes);

/// The same for an axis-aligned solid box, in float: every segment passes through the
/// interior of `solid` shrunk by kBoxShrink on every side (the shrink absorbs float
/// rounding, so `true` also holds for the exact box). Far cheaper than the planes.
/// `solid` must be thicker than 2 kBoxShrink on every axis (OccluderWorld::solid_box()
/// gives no other): a thinner one, shrunk, would turn inside out and block more than it.
/// With SSE2, four pairs of sides at a time; the answers are shaft_blocked_by_box_scalar()'s.
[[nodiscard]] bool shaft_blocked_by_box(const Aabb& region, const Aabb& box, const Aabb& solid);

/// shaft_blocked_by_box() one pair of sides at a time in scalar floats: the path
/// without SSE2, and the twin the vector path is tested and timed against.
[[nodiscard]] bool shaft_blocked_by_box_scalar(const Aabb& region, const Aabb& box,
                                               const Aabb& solid);

/// A segment a-b as the box tests read it: its start, b - a, and 1 / (b - a) per axis
/// (infinite where b - a is 0, and then unused), worked out once for the many boxes one
/// segment is tested against.
struct SegmentRay {
    glm::vec3 from{0.0f};
    glm::vec3 dir{0.0f};
    glm::vec3 inv{0.0f};
    [[nodiscard]] static SegmentRay between(glm::vec3 a, glm::vec3 b) {
        const glm::vec3 d = b - a;
        return {a, d, glm::vec3(1.0f / d.x, 1.0f / d.y, 1.0f / d.z)};
    }
};

/// True when the open segment `s` passes through the interior of `solid` shrunk by
/// kBoxShrink (positive length inside; float). `true` implies segment_blocked_by() for
/// the box's six planes. `solid` as for shaft_blocked_by_box().
[[nodiscard]] inline bool segment_through_box(const SegmentRay& s, const Aabb& solid) {
    const glm::vec3 lo = solid.min + glm::vec3(kBoxShrink);
    const glm::vec3 hi = solid.max - glm::vec3(kBoxShrink);
    float t0 = 0.0f;
    float t1 = 1.0f;
    for (int axis = 0; axis < 3; ++axis) {
        if (s.dir[axis] == 0.0f) {
            if (!(s.from[axis] > lo[axis] && s.from[axis] < hi[axis])) {
                return false;
            }
            continue;
        }
        float ta = (lo[axis] - s.from[axis]) * s.inv[axis];
        float tb = (hi[axis] - s.from[axis]) * s.inv[axis];
        if (ta > tb) {
            std::swap(ta, tb);
        }
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t1 - t0 <= 1.0e-6f) {
            return false;
        }
    }
    return true;
}

/// segment_through_box() for the segment a-b.
[[nodiscard]] inline bool segment_through_box(glm::vec3 a, glm::vec3 b, const Aabb& solid) {
    return segment_through_box(SegmentRay::between(a, b), solid);
}

/// Shaft stage over a world: `occluded` when some single occluder blocks every
/// segment from `region` to `box` (exact per occluder, see above) or, with fusion on,
/// when the occluders cut by one of a few axis-aligned planes through the walls the
/// centre segment crosses cover every crossing together (cut_plane_fusion.hpp), or,
/// with portals on, when every part of such a plane the occluders leave open (a
/// "portal": a doorway, the gap beside a wall) is itself hidden from the region or
/// hides the box from itself (tested the same way, one level down);
/// `visible` otherwise (may be a false positive). Occluders that cut into the region
/// take part: the arguments need only convexity.
///
/// Why portals are conservative: a segment from a point of the region to a point of
/// the box crosses the plane once, either inside a cut occluder (blocked) or at a
/// point x of some open part P. If no segment from the region to P gets through, the
/// part of the segment before x is blocked; if no segment from P to the box gets
/// through, the part after x is. Either way the segment is blocked. This is what
/// closes "a doorway, then a wall behind it", which no single plane shows.
class ShaftOcclusion {
public:
    /// `world`, `grid` and `bvh` (built over `world`) must outlive this.
    /// `portal_depth`: levels of portal tests below the top one (0: none; needs fusion).
    /// `bvh` (optional) proves a centre segment clear without the grid walk when no
    /// occluder blocks it, and checks witness segments (segment_clear()). The answers
    /// and hints are the same with it or without it, except that without it a witness
    /// may pass closer than kWitnessMargin to an occluder in a cell the walk does not
    /// cross.
    explicit ShaftOcclusion(const OccluderWorld& world, const OccluderGrid& grid,
                            bool fusion = true, int portal_depth = kDefaultPortalDepth,
                            const OccluderBvh* bvh = nullptr)
        : world_(&world), grid_(&grid), bvh_(bvh), fusion_(fusion),
          portal_depth_(fusion ? std::min(portal_depth, kMaxPortalDepth) : 0) {}

    /// Per-thread memory, reused between tests.
    struct Scratch {
        OccluderGrid::Scratch grid;
        CutPlaneFusion::Scratch fusion;
        std::vector<CutPlane> planes;
        std::vector<OccluderId> plane_sources; ///< the occluder each plane runs through
        /// Per portal level: that level's cut planes and open parts (kept across the
        /// tests one level down, which reuse the fields above).
        std::array<std::vector<CutPlane>, 4> portal_planes;
        std::array<std::vector<OccluderId>, 4> portal_sources;
        std::array<std::vector<Aabb>, 4> portals;
        int portal_budget = 0; ///< sub-tests left for the current top-level test
    };

    /// `hint` (optional, in/out): what decided the box last time, tried first: 0
    /// (nothing), 1 + the id of an occluder, or kPortalHint | axis << 29 | id for the
    /// plane through the middle of occluder `id` across `axis`, whose fusion test, then
    /// portal tests, proved it hidden; or a witness (kWitnessHint), a segment found clear
    /// when the box was last shown visible. Written here when one of the proofs shows
    /// the box hidden; when a visible box's centre segment was blocked, to a witness or
    /// a record of the search (kNoWitness); after failed portal tests, to their skip
    /// count (kPortalSkips); to 0 otherwise. A hint orders the work and never changes
    /// what an answer promises: a stale one is tried and dropped.
    [[nodiscard]] Visibility test(const Aabb& region, const Aabb& box, Scratch& scratch,
                                  std::uint32_t* hint = nullptr) const;

    /// Occluders given the full 64-segment test per query at most (those that block
    /// the centre-to-centre segment); past it no further single occluder is tried.
    static constexpr int kMaxFullTests = 16;
    /// Cut planes tried for fusion per query at most: the axis planes through the
    /// middle of the occluders that block the centre segment, nearest the region
    /// first. (On oa_dm4, 3 planes prove 98% of what 6 do at 60% of the cost.)
    static constexpr std::size_t kMaxCutPlanes = 3;
    static constexpr int kDefaultPortalDepth = 2;
    static constexpr std::uint32_t kPortalHint = 0x80000000u;
    /// Tag of a witness hint, kWitnessHint | r << 3 | b: the segment from corner r of the
    /// region to corner b of the box (bit 0 of a corner is max x, bit 1 max y, bit 2 max
    /// z). While that segment stays clear of every occluder by kWitnessMargin it shows
    /// the box visible (some eye of the region sees a point of the box, and no proof,
    /// with its tolerances, could hide it), so a box that stays in view costs one walk a
    /// test instead of failing the proofs again; the first test that finds it blocked
    /// drops it and runs the full test. Worlds hold at most 2^29 occluders
    /// (OccluderWorld::kMaxOccluders), so no occluder or portal hint has these top bits.
    static constexpr std::uint32_t kWitnessHint = 0x60000000u;
    static constexpr std::uint32_t kWitnessCorners = 0x3fu; ///< r << 3 | b
    /// How far a witness keeps from every occluder: more than the proofs' own slack
    /// (kBoxShrink, kPortalPad, CutPlaneFusion::kNoiseWidth), so that none of them can
    /// call hidden a box a witness shows. [Units: world units]
    static constexpr float kWitnessMargin = 1.0f / 16.0f;
    /// kWitnessHint | kNoWitness | level << 4 | skips: the last search found no witness,
    /// so the pair's next `skips` searches are skipped; a search that fails after them
    /// skips 2^(level + 1) - 1 (3, 7, then 15): on closed maps few boxes in view have a
    /// clear corner segment above the blocked centre, and a failed search costs walks.
    /// With portal tests, failed ones put their skip count in the hint instead, so there
    /// a search that keeps failing is tried every other test.
    static constexpr std::uint32_t kNoWitness = 0x40u;
    /// Boxes with a longer side skip the portal tests (TBVs of fast entities and boxes
    /// of entity clusters seldom pass them and cost the most; docs/region-visibility.md
    /// has what the bound saves) and the search for a witness (their hints are not kept
    /// while they are visible). Only the queried box counts, not the portals of the
    /// sub-tests.
    /// [Units: world units]
    static constexpr float kMaxPortalBoxSide = 200.0f;
    /// A centre segment is checked in the tree (when there is one) before the grid walk
    /// only when it spans more grid cells than this (its length along the three axes
    /// over the cell's edge): a short walk costs less than the tree's levels.
    static constexpr float kMinTreeCells = 8.0f;
    /// Hinted queries after a failed portal test that skip the portal tests.
    static constexpr std::uint32_t kPortalSkips = 1;
    static constexpr int kMaxPortalDepth = 4;
    /// Open parts of a plane given sub-tests at most; a plane leaving more is skipped.
    static constexpr std::size_t kMaxPortals = 8;
    /// Sub-tests (two per open part at most) per top-level test, all levels together.
    static constexpr int kPortalBudget = 48;
    /// Open parts are widened by this in the plane (rounding from double). [Units: world units]
    static constexpr float kPortalPad = 1.0f / 64.0f;

private:
    /// test() with `depth` portal levels left; `cheap_done`: the single-occluder and
    /// fusion tests of this pair already failed, only the portal tests are left.
    [[nodiscard]] Visibility test_at(const Aabb& region, const Aabb& box, Scratch& scratch,
                                     std::uint32_t* hint, int depth, bool cheap_done = false) const;
    /// True when the segment a-b keeps kWitnessMargin from every occluder (with a tree),
    /// or from every occluder the grid walk finds along it (without one).
    [[nodiscard]] bool segment_clear(glm::vec3 a, glm::vec3 b, Scratch& scratch) const;
    /// The witness hint of the first clear one of a few corner segments from `region`
    /// to `box`, or 0 when they are all blocked.
    [[nodiscard]] std::uint32_t find_witness(const Aabb& region, const Aabb& box,
                                             Scratch& scratch) const;
    /// True when, for one of scratch.planes, the cut occluders cover it (fusion), or
    /// every open part is hidden from `region` or hides `box` (sub-tests at `depth` - 1).
    /// Returns the index in scratch.planes of the plane that proved it, or -1.
    [[nodiscard]] int hidden_through_portals(const Aabb& region, const Aabb& box, Scratch& scratch,
                                             int depth) const;

    const OccluderWorld* world_;
    const OccluderGrid* grid_;
    const OccluderBvh* bvh_;
    bool fusion_;
    int portal_depth_;
};

} // namespace dsoc::visibility
