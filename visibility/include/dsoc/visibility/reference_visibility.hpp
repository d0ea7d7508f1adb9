#pragma once
// Exact brute-force visibility: the slow, obviously-correct twin of the culling
// backends. Used as the oracle of the property tests and the baseline of the
// benchmarks. Never use it per tick on a server.

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <span>
#include <vector>

namespace dsoc::visibility {

/// True when the open segment (a, b) passes through the interior of the convex
/// solid { x : dot(n_i, x) <= d_i }: the part of the segment strictly inside every
/// plane has positive length (more than `1e-6` of the segment, relatively). Grazing
/// a face, an edge or a vertex is NOT blocking. Double precision.
[[nodiscard]] bool segment_blocked_by(glm::vec3 a, glm::vec3 b, std::span<const Plane> planes);

/// Reference answers over a world. Brute force: every query scans every occluder
/// (after a bounding-box reject). Thread-safe const queries.
class ReferenceVisibility {
public:
    explicit ReferenceVisibility(const OccluderWorld& world) : world_(&world) {}

    /// True when some occluder blocks the segment from `eye` to `point`.
    [[nodiscard]] bool segment_blocked(glm::vec3 eye, glm::vec3 point) const;

    /// Samples on the box: a `grid` x `grid` lattice on each face (grid >= 2, so the
    /// corners and edges are included) plus the centre. Visible when any sample is
    /// seen from the eye. The box is visible if it contains the eye.
    /// Not exact for the box as a whole (a gap between samples may be missed), but
    /// every `visible` answer is a certificate: a real unblocked segment exists.
    [[nodiscard]] Visibility test_box(glm::vec3 eye, const Aabb& box, int grid = 5) const;

    /// The sample points test_box uses, appended to `out` (deduplicated corners).
    static void box_samples(const Aabb& box, int grid, std::vector<glm::vec3>& out);

private:
    const OccluderWorld* world_;
};

} // namespace dsoc::visibility
