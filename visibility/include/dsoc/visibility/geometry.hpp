#pragma once
// Basic geometric primitives of the visibility core. World units throughout (Quake 3
// units for OpenArena maps), z is up. Plain value types; no allocation.

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace dsoc::visibility {

/// Axis-aligned box [min, max]. An empty box has min > max on some axis
/// (Aabb::empty()); extending an empty box by a point gives that point.
struct Aabb {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{std::numeric_limits<float>::lowest()};

    static Aabb empty() { return {}; }
    static Aabb from_center_half_extents(glm::vec3 center, glm::vec3 half) {
        return {center - half, center + half};
    }

    [[nodiscard]] bool is_empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    [[nodiscard]] glm::vec3 center() const { return (min + max) * 0.5f; }
    [[nodiscard]] glm::vec3 half_extents() const { return (max - min) * 0.5f; }
    [[nodiscard]] glm::vec3 size() const { return max - min; }

    void extend(glm::vec3 p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void extend(const Aabb& b) {
        min = glm::min(min, b.min);
        max = glm::max(max, b.max);
    }
    /// Grows the box by `r` on every side (r >= 0).
    [[nodiscard]] Aabb expanded(float r) const { return {min - glm::vec3(r), max + glm::vec3(r)}; }
    [[nodiscard]] Aabb expanded(glm::vec3 r) const { return {min - r, max + r}; }

    /// Closed-interval tests: touching counts as overlap / containment.
    [[nodiscard]] bool contains(glm::vec3 p) const {
        return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
               p.z <= max.z;
    }
    [[nodiscard]] bool contains(const Aabb& b) const {
        return b.min.x >= min.x && b.min.y >= min.y && b.min.z >= min.z && b.max.x <= max.x &&
               b.max.y <= max.y && b.max.z <= max.z;
    }
    [[nodiscard]] bool overlaps(const Aabb& b) const {
        return min.x <= b.max.x && max.x >= b.min.x && min.y <= b.max.y && max.y >= b.min.y &&
               min.z <= b.max.z && max.z >= b.min.z;
    }
};

/// Sphere; radius >= 0.
struct Sphere {
    glm::vec3 center{0.0f};
    float radius = 0.0f;
};

/// Plane as the half-space boundary dot(normal, x) = distance. `normal` is unit
/// length and, for a brush side, points out of the solid: the solid is the set
/// where dot(normal, x) <= distance.
struct Plane {
    glm::vec3 normal{0.0f, 0.0f, 1.0f};
    float distance = 0.0f;

    /// Signed distance of `p`; negative inside the half-space the plane bounds.
    [[nodiscard]] float signed_distance(glm::vec3 p) const {
        return normal.x * p.x + normal.y * p.y + normal.z * p.z - distance;
    }
    [[nodiscard]] glm::vec4 as_vec4() const { return {normal, distance}; }
};

/// The slab test of the segment from + t * dir against the closed box `box`, given
/// `inv` = 1 / dir per axis: narrows [t0, t1] to the parameters at which the segment is
/// in the box; false when nothing is left. An axis where dir is 0, or so small that
/// 1 / dir is not finite, leaves [t0, t1] as it is when `from` lies within the box's
/// extent on that axis, and empties it when not (no infinity times 0 can make a NaN).
[[nodiscard]] inline bool clip_segment_to_box(glm::vec3 from, glm::vec3 inv, const Aabb& box,
                                              float& t0, float& t1) {
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(inv[a])) {
            if (from[a] < box.min[a] || from[a] > box.max[a]) {
                return false;
            }
            continue;
        }
        float ta = (box.min[a] - from[a]) * inv[a];
        float tb = (box.max[a] - from[a]) * inv[a];
        if (ta > tb) {
            std::swap(ta, tb);
        }
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) {
            return false;
        }
    }
    return true;
}

/// Squared distance from `p` to the closest point of `box` (0 inside).
[[nodiscard]] inline float distance_squared(const Aabb& box, glm::vec3 p) {
    const glm::vec3 d = glm::max(glm::max(box.min - p, p - box.max), glm::vec3(0.0f));
    return glm::dot(d, d);
}

/// Squared distance from `p` to the farthest point of `box`.
[[nodiscard]] inline float max_distance_squared(const Aabb& box, glm::vec3 p) {
    const glm::vec3 d = glm::max(glm::abs(box.min - p), glm::abs(box.max - p));
    return glm::dot(d, d);
}

/// True when the sphere and the box share a point (closed sets).
[[nodiscard]] inline bool overlaps(const Sphere& s, const Aabb& box) {
    return distance_squared(box, s.center) <= s.radius * s.radius;
}

/// Smallest sphere containing both spheres.
[[nodiscard]] inline Sphere enclosing_sphere(const Sphere& a, const Sphere& b) {
    const glm::vec3 d = b.center - a.center;
    const float dist = glm::length(d);
    if (dist + b.radius <= a.radius) {
        return a;
    }
    if (dist + a.radius <= b.radius) {
        return b;
    }
    const float radius = (dist + a.radius + b.radius) * 0.5f;
    const glm::vec3 center = a.center + d * ((radius - a.radius) / dist);
    // Round up so float error never leaves a child sphere poking out.
    return {center, radius * (1.0f + 1e-6f) + 1e-6f};
}

/// The box's extent along `normal` from its centre: max over corners of
/// dot(normal, corner - centre). Used for box-versus-plane classification.
[[nodiscard]] inline float projected_radius(const Aabb& box, glm::vec3 normal) {
    const glm::vec3 h = box.half_extents();
    return std::abs(normal.x) * h.x + std::abs(normal.y) * h.y + std::abs(normal.z) * h.z;
}

/// A convex volume bounded by up to six planes, normals pointing OUT (the inside is
/// where every signed_distance <= 0), e.g. a view frustum. Plane order is free.
struct Frustum {
    Plane planes[6];
    int plane_count = 6;

    /// Conservative box test: false only when the box lies entirely outside one
    /// plane. A box near a frustum corner may answer true while outside.
    [[nodiscard]] bool may_overlap(const Aabb& box) const {
        const glm::vec3 c = box.center();
        for (int i = 0; i < plane_count; ++i) {
            if (planes[i].signed_distance(c) > projected_radius(box, planes[i].normal)) {
                return false;
            }
        }
        return true;
    }
    [[nodiscard]] bool may_overlap(const Sphere& s) const {
        for (int i = 0; i < plane_count; ++i) {
            if (planes[i].signed_distance(s.center) > s.radius) {
                return false;
            }
        }
        return true;
    }
    /// A frustum from an eye, a unit forward and up direction, vertical field of view
    /// (radians, (0, pi)), aspect (width / height) and near/far distances (0 < near < far).
    [[nodiscard]] static Frustum perspective(glm::vec3 eye, glm::vec3 forward, glm::vec3 up,
                                             float fov_y, float aspect, float near_distance,
                                             float far_distance);
};

} // namespace dsoc::visibility
