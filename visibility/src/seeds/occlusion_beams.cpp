// A beam of occluder O from the eye E (outside O) is the intersection of
//  * O's front-facing planes (those E is outside of), and
//  * one plane through E and each silhouette edge (an edge between a front-facing
//    and a back-facing face), oriented so that O is inside.
// A point P strictly inside all of them lies strictly inside the cone of rays from E
// that hit O, and is not in front of O's entry point (it is inside every front
// plane), so the segment E->P crosses O's interior. See docs/visibility.md.

#include "dsoc/visibility/seeds/occlusion_beams.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace dsoc::visibility {
namespace {

/// Relative margin: an item must be inside every beam plane by this share of its
/// distance from the eye (plus a small absolute amount), absorbing float error.
constexpr float kRelativeMargin = 1.0e-4f;
constexpr float kAbsoluteMargin = 1.0e-3f;

} // namespace

bool OcclusionBeams::add_beam(const OccluderWorld& world, OccluderId id) {
    if (!world.is_closed(id)) {
        return false;
    }
    const auto face_planes = world.face_planes(id);
    const ConvexPolyhedron& poly = world.occluder(id);
    const glm::dvec3 eye(eye_);
    front_scratch_.resize(face_planes.size());
    offset_scratch_.resize(face_planes.size());
    bool any_front = false;
    for (std::size_t f = 0; f < face_planes.size(); ++f) {
        // Eye-relative plane offsets, in double: coordinates reach thousands of units
        // while the eye may be a unit away. Faces the eye is on or near count as
        // neither: then the eye is too close to O for a stable beam, and we make none.
        const double s = glm::dot(glm::dvec3(face_planes[f].normal), eye) -
                         static_cast<double>(face_planes[f].distance);
        if (std::abs(s) < static_cast<double>(kAbsoluteMargin)) {
            return false;
        }
        offset_scratch_[f] = -s;
        front_scratch_[f] = s > 0.0 ? 1 : 0;
        any_front = any_front || s > 0.0;
    }
    if (!any_front) {
        return false; // eye inside O
    }
    const auto first = static_cast<std::uint32_t>(planes_.size());
    for (std::size_t f = 0; f < face_planes.size(); ++f) {
        if (front_scratch_[f] != 0) {
            planes_.push_back(Plane{face_planes[f].normal, static_cast<float>(offset_scratch_[f])});
        }
    }
    // The vertex average is inside O (a convex combination of its vertices); the
    // bounding-sphere centre need not be.
    glm::dvec3 inside_point(0.0);
    double largest_coordinate = 0.0;
    for (const glm::vec3& v : poly.vertices()) {
        inside_point += glm::dvec3(v) - eye;
        largest_coordinate = std::max(largest_coordinate, static_cast<double>(glm::length(v)));
    }
    inside_point /= static_cast<double>(poly.vertices().size());
    double nearest_vertex = std::numeric_limits<double>::max();
    for (const OccluderEdge& e : world.edges(id)) {
        if (front_scratch_[e.face_a] == front_scratch_[e.face_b]) {
            continue;
        }
        const glm::dvec3 a = glm::dvec3(poly.vertices()[e.v0]) - eye;
        const glm::dvec3 b = glm::dvec3(poly.vertices()[e.v1]) - eye;
        glm::dvec3 n = glm::cross(a, b);
        const double len = glm::length(n);
        if (!(len > 1.0e-6 * glm::length(a) * glm::length(b))) {
            planes_.resize(first); // eye in line with an edge: no stable beam
            return false;
        }
        n /= len;
        // Orient so O is inside the cone; the plane contains the eye (offset 0).
        if (glm::dot(n, inside_point) > 0.0) {
            n = -n;
        }
        nearest_vertex = std::min(nearest_vertex, std::min(glm::length(a), glm::length(b)));
        planes_.push_back(Plane{glm::vec3(n), 0.0f});
    }
    // The stored vertices are the exact ones rounded to float (error below
    // |v| * 2^-23 with room to spare); a silhouette plane through a vertex at distance
    // L from the eye may turn by that error / L, moving it by (error / L) * D at
    // distance D. Tests add that as margin.
    const double vertex_error = largest_coordinate * std::ldexp(1.0, -22);
    const float slack = static_cast<float>(vertex_error / std::max(nearest_vertex, 1.0e-3));
    beams_.push_back({first, static_cast<std::uint32_t>(planes_.size()) - first, slack});
    return true;
}

template <class InsideFn>
bool OcclusionBeams::inside_some_beam(InsideFn&& inside) const {
    for (const Beam& beam : beams_) {
        bool all = true;
        for (std::uint32_t i = 0; i < beam.plane_count && all; ++i) {
            all = inside(planes_[beam.first_plane + i], beam.angular_slack);
        }
        if (all) {
            return true;
        }
    }
    return false;
}

void OcclusionBeams::build(glm::vec3 eye, const OccluderWorld& world, const BspTree& bsp) {
    eye_ = eye;
    beams_.clear();
    planes_.clear();
    stats_ = {};
    const float max_sq = config_.max_occluder_distance * config_.max_occluder_distance;
    int budget = config_.max_beams;
    if (budget <= 0) {
        return;
    }
    bsp.traverse_nearest_first(
        eye, heap_,
        [&](const BspNode& node) {
            if (distance_squared(node.bounds, eye) > max_sq) {
                return false;
            }
            if (test_sphere(node.sphere) == Visibility::occluded) {
                ++stats_.nodes_culled;
                return false;
            }
            return true;
        },
        [&](OccluderId id) {
            const Sphere& s = world.occluder(id).bounding_sphere();
            const float dist = glm::length(s.center - eye);
            if (s.radius < config_.min_angular_radius * dist) {
                return true;
            }
            if (add_beam(world, id)) {
                ++stats_.beams;
                --budget;
            }
            return budget > 0;
        });
}

Visibility OcclusionBeams::test_sphere(const Sphere& sphere) const {
    // Eye-relative centre (planes are stored relative to the eye), in double.
    const glm::vec3 c(glm::dvec3(sphere.center) - glm::dvec3(eye_));
    const float dist = glm::length(c);
    const float margin = sphere.radius + kRelativeMargin * dist + kAbsoluteMargin;
    const bool hidden = inside_some_beam([&](const Plane& p, float slack) {
        return p.signed_distance(c) <= -(margin + slack * (dist + sphere.radius));
    });
    return hidden ? Visibility::occluded : Visibility::visible;
}

Visibility OcclusionBeams::test_box(const Aabb& box) const {
    if (box.is_empty() || box.contains(eye_)) {
        return Visibility::visible;
    }
    const Aabb rel{glm::vec3(glm::dvec3(box.min) - glm::dvec3(eye_)),
                   glm::vec3(glm::dvec3(box.max) - glm::dvec3(eye_))};
    const glm::vec3 c = rel.center();
    const float far = std::sqrt(max_distance_squared(rel, glm::vec3(0.0f)));
    const float base_margin = kRelativeMargin * far + kAbsoluteMargin;
    const bool hidden = inside_some_beam([&](const Plane& p, float slack) {
        return p.signed_distance(c) <=
               -(projected_radius(rel, p.normal) + base_margin + slack * far);
    });
    return hidden ? Visibility::occluded : Visibility::visible;
}

} // namespace dsoc::visibility
