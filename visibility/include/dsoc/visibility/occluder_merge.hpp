#pragma once
// Merging occluders whose union is exactly convex, before culling.
//
// Level designers build a wall from many brushes. Every seam between two brushes
// is an edge where a conservative culler loses coverage (a from-region culler loses
// a band as wide as the region's parallax there), so a wall of ten brushes occludes
// far less than one brush of the same shape. Two axis-aligned boxes that share a
// whole face (or overlap with the same cross-section) are exactly one box: merging
// them changes no visibility answer and removes the seam.

#include "dsoc/visibility/convex_polyhedron.hpp"

#include <vector>

namespace dsoc::visibility {

struct OccluderMergeStats {
    std::size_t input = 0;
    std::size_t boxes = 0; ///< inputs that are axis-aligned boxes
    std::size_t output = 0;
};

/// Returns the occluders with every group of axis-aligned boxes that tile a larger
/// box replaced by that box (greedy, along x, y and z in turn, until nothing merges).
/// Non-box occluders are returned unchanged. `tolerance` (world units) is how far
/// apart two faces or extents may be and still count as equal; the merged box is
/// the exact union's bounds, so a tolerance only ever merges boxes whose union's
/// bounds are covered up to `tolerance` — keep it tiny (default 1/64 unit).
[[nodiscard]] std::vector<ConvexPolyhedron>
merge_box_occluders(const std::vector<ConvexPolyhedron>& occluders,
                    OccluderMergeStats* stats = nullptr, float tolerance = 1.0f / 64.0f);

} // namespace dsoc::visibility
