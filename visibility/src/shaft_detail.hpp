#pragma once
// Helpers the single-occluder shaft tests and ShaftOcclusion share (internal to
// dsoc_visibility).

#include "dsoc/visibility/geometry.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace dsoc::visibility::shaft_detail {

/// Corner k of `b`: bit 0 of k picks max x, bit 1 max y, bit 2 max z.
inline glm::vec3 corner(const Aabb& b, std::uint32_t k) {
    return {(k & 1u) ? b.max.x : b.min.x, (k & 2u) ? b.max.y : b.min.y,
            (k & 4u) ? b.max.z : b.min.z};
}

/// The eight corners of `b`, corner k at index k.
inline std::array<glm::vec3, 8> corners(const Aabb& b) {
    std::array<glm::vec3, 8> c;
    for (std::uint32_t k = 0; k < 8; ++k) {
        c[k] = corner(b, k);
    }
    return c;
}

/// Planes a solid may have for the plane buffers (no brush has more; past it,
/// shaft_blocked_by() takes the scalar path and a witness counts the solid as in its way).
inline constexpr std::size_t kMaxBufferedPlanes = 32;

/// Does the segment from + t * dir, t in [0, 1], touch the closed box? `inv` is 1 / dir
/// per axis.
inline bool segment_hits_box(glm::vec3 from, glm::vec3 inv, const Aabb& box) {
    float t0 = 0.0f;
    float t1 = 1.0f;
    return clip_segment_to_box(from, inv, box, t0, t1);
}

} // namespace dsoc::visibility::shaft_detail
