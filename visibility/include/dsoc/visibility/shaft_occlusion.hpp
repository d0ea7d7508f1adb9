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
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>
#include <vector>

namespace dsoc::visibility {

/// True when every segment from a point of `region` to a point of `box` passes
/// through the interior of the convex solid { x : dot(n_i, x) <= d_i }.
[[nodiscard]] bool shaft_blocked_by(const Aabb& region, const Aabb& box,
                                    std::span<const Plane> planes);

/// A uniform grid over an occluder world's bounds listing the occluders that
/// overlap each cell, to find the occluders that may cut a shaft. Immutable after
/// construction; queries are const and thread-safe given a caller-owned scratch.
class OccluderGrid {
public:
    /// `cell_size` in world units (> 0).
    explicit OccluderGrid(const OccluderWorld& world, float cell_size = 256.0f);

    /// Scratch for one querying thread (a visit stamp per occluder).
    struct Scratch {
        std::vector<std::uint32_t> stamp;
        std::uint32_t epoch = 0;
        std::vector<OccluderId> found;
    };

    /// Occluders whose bounds overlap `box`, each once, into scratch.found.
    void query(const Aabb& box, Scratch& scratch) const;

    /// Occluders in the cells the segment `from`-`to` passes through (a 3D DDA walk),
    /// each once, into scratch.found: every occluder that intersects the segment is
    /// among them (up to float rounding at cell borders, which can only drop one).
    void query_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch) const;

private:
    const OccluderWorld* world_;
    Aabb bounds_;
    float cell_size_;
    int dims_[3] = {1, 1, 1};
    std::vector<std::uint32_t> cell_start_; ///< CSR offsets, one more than cells
    std::vector<OccluderId> cell_items_;
};

/// Shaft stage over a world: `occluded` when some single occluder blocks every
/// segment from `region` to `box` (exact per occluder, see above); `visible`
/// otherwise (may be a false positive). Occluders that cut into the region take part:
/// the argument needs only convexity.
class ShaftOcclusion {
public:
    explicit ShaftOcclusion(const OccluderWorld& world, const OccluderGrid& grid)
        : world_(&world), grid_(&grid) {}

    [[nodiscard]] Visibility test(const Aabb& region, const Aabb& box,
                                  OccluderGrid::Scratch& scratch) const;

    /// Occluders given the full 64-segment test per query at most (those that block
    /// the centre-to-centre segment); past it the answer is `visible`.
    static constexpr int kMaxFullTests = 16;

private:
    const OccluderWorld* world_;
    const OccluderGrid* grid_;
};

} // namespace dsoc::visibility
