// Brush construction by clipping: every plane starts as a huge square lying on it,
// which is chopped by every other plane (the Quake tools' method). What survives is
// the face; vertices are the merged face corners. All clipping runs in double
// precision; only the final vertices are stored as float.

#include "dsoc/visibility/convex_polyhedron.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>

namespace dsoc::visibility {
namespace {

using dvec3 = glm::dvec3;

/// Half-size of the square each plane starts as. A vertex farther than
/// kUnboundedLimit from the origin can only come from this square's rim, so the
/// region is unbounded. Map coordinates stay far below both.
constexpr double kBaseWindingHalfSize = 1.0e8;
constexpr double kUnboundedLimit = 1.0e7;
/// Points within this distance of a clipping plane count as on it (kept).
constexpr double kClipEpsilon = 1.0e-5;

struct DPlane {
    dvec3 normal;
    double distance;
    [[nodiscard]] double signed_distance(const dvec3& p) const {
        return glm::dot(normal, p) - distance;
    }
};

using Winding = std::vector<dvec3>;

Winding base_winding(const DPlane& plane) {
    // Pick the major axis to build a stable tangent frame.
    const dvec3 n = plane.normal;
    const dvec3 a = std::abs(n.z) < 0.9 ? dvec3(0, 0, 1) : dvec3(1, 0, 0);
    const dvec3 u = glm::normalize(glm::cross(a, n));
    const dvec3 v = glm::cross(n, u);
    const dvec3 origin = n * plane.distance;
    const double s = kBaseWindingHalfSize;
    // Counter-clockwise seen from outside (from +normal): u, v, n is right-handed.
    return {origin - u * s - v * s, origin + u * s - v * s, origin + u * s + v * s,
            origin - u * s + v * s};
}

/// Keeps the part of `w` with signed_distance <= kClipEpsilon. `scratch` is reused.
void clip_winding(Winding& w, const DPlane& plane, Winding& scratch) {
    scratch.clear();
    const std::size_t count = w.size();
    if (count == 0) {
        return;
    }
    bool any_outside = false;
    for (const dvec3& p : w) {
        if (plane.signed_distance(p) > kClipEpsilon) {
            any_outside = true;
            break;
        }
    }
    if (!any_outside) {
        return;
    }
    for (std::size_t i = 0; i < count; ++i) {
        const dvec3& p = w[i];
        const dvec3& q = w[(i + 1) % count];
        const double dp = plane.signed_distance(p);
        const double dq = plane.signed_distance(q);
        const bool p_in = dp <= kClipEpsilon;
        const bool q_in = dq <= kClipEpsilon;
        if (p_in) {
            scratch.push_back(p);
        }
        if (p_in != q_in) {
            // Crossing strictly between p and q: interpolate at the plane itself.
            const double t = dp / (dp - dq);
            scratch.push_back(p + (q - p) * t);
        }
    }
    w.swap(scratch);
}

bool is_finite(const Plane& p) {
    return std::isfinite(p.normal.x) && std::isfinite(p.normal.y) && std::isfinite(p.normal.z) &&
           std::isfinite(p.distance);
}

std::string plane_text(std::size_t index, const Plane& p) {
    char buffer[160];
    std::snprintf(buffer, sizeof buffer, "plane %zu (normal %g %g %g, distance %g)", index,
                  static_cast<double>(p.normal.x), static_cast<double>(p.normal.y),
                  static_cast<double>(p.normal.z), static_cast<double>(p.distance));
    return buffer;
}

ConvexPolyhedron fail(PolyhedronResult& result, PolyhedronError error, std::string detail) {
    result.error = error;
    result.detail = std::move(detail);
    return {};
}

} // namespace

const char* to_string(PolyhedronError error) noexcept {
    switch (error) {
    case PolyhedronError::none:
        return "none";
    case PolyhedronError::too_few_planes:
        return "too_few_planes";
    case PolyhedronError::non_finite_plane:
        return "non_finite_plane";
    case PolyhedronError::unbounded:
        return "unbounded";
    case PolyhedronError::empty:
        return "empty";
    }
    return "unknown";
}

ConvexPolyhedron ConvexPolyhedron::from_planes(std::span<const Plane> planes,
                                               PolyhedronResult& result, float tolerance) {
    result = {};
    if (planes.size() < 4) {
        return fail(result, PolyhedronError::too_few_planes,
                    std::to_string(planes.size()) + " planes; a bounded solid needs at least 4");
    }
    if (!(tolerance >= 0.0f) || !std::isfinite(tolerance)) {
        tolerance = 1.0f / 64.0f;
    }
    const double tol = static_cast<double>(tolerance);

    std::vector<DPlane> dplanes;
    dplanes.reserve(planes.size());
    std::vector<Plane> normalized;
    normalized.reserve(planes.size());
    for (std::size_t i = 0; i < planes.size(); ++i) {
        const Plane& p = planes[i];
        if (!is_finite(p)) {
            return fail(result, PolyhedronError::non_finite_plane,
                        plane_text(i, p) + " has a NaN or infinite component");
        }
        const dvec3 n(p.normal);
        const double length = glm::length(n);
        if (!(length > 1.0e-12)) {
            return fail(result, PolyhedronError::non_finite_plane,
                        plane_text(i, p) + " has a zero normal");
        }
        const DPlane dp{n / length, static_cast<double>(p.distance) / length};
        dplanes.push_back(dp);
        normalized.push_back(Plane{glm::vec3(dp.normal), static_cast<float>(dp.distance)});
    }

    // Faces: clip each plane's base square by all others. A later near-duplicate of
    // an earlier plane yields no face of its own (the earlier one carries it).
    std::vector<Winding> windings(dplanes.size());
    Winding scratch;
    scratch.reserve(64);
    for (std::size_t i = 0; i < dplanes.size(); ++i) {
        Winding& w = windings[i];
        w = base_winding(dplanes[i]);
        for (std::size_t j = 0; j < dplanes.size() && !w.empty(); ++j) {
            if (j == i) {
                continue;
            }
            const bool same_plane = glm::dot(dplanes[i].normal, dplanes[j].normal) > 1.0 - 1.0e-9 &&
                                    std::abs(dplanes[i].distance - dplanes[j].distance) <= 1.0e-6;
            if (same_plane) {
                if (j < i) {
                    w.clear();
                }
                continue;
            }
            clip_winding(w, dplanes[j], scratch);
        }
        if (w.size() < 3) {
            w.clear();
        }
    }

    // Vertices: merge face corners closer than the tolerance.
    std::vector<dvec3> merged;
    std::vector<std::vector<std::uint32_t>> face_indices(dplanes.size());
    const double merge_distance = std::max(tol, 1.0e-4);
    const double merge_sq = merge_distance * merge_distance;
    bool unbounded = false;
    for (std::size_t i = 0; i < windings.size(); ++i) {
        for (const dvec3& p : windings[i]) {
            if (std::abs(p.x) > kUnboundedLimit || std::abs(p.y) > kUnboundedLimit ||
                std::abs(p.z) > kUnboundedLimit) {
                unbounded = true;
            }
            std::uint32_t index = static_cast<std::uint32_t>(merged.size());
            for (std::uint32_t k = 0; k < merged.size(); ++k) {
                const dvec3 d = merged[k] - p;
                if (glm::dot(d, d) <= merge_sq) {
                    index = k;
                    break;
                }
            }
            if (index == merged.size()) {
                merged.push_back(p);
            }
            auto& loop = face_indices[i];
            if (loop.empty() || loop.back() != index) {
                loop.push_back(index);
            }
        }
        auto& loop = face_indices[i];
        while (loop.size() > 1 && loop.front() == loop.back()) {
            loop.pop_back();
        }
        // A loop may revisit a vertex after merging (a sliver); drop such faces' repeats.
        if (loop.size() < 3) {
            loop.clear();
        }
    }
    if (unbounded) {
        return fail(result, PolyhedronError::unbounded,
                    "the half-spaces leave a direction open (a vertex beyond 1e7 units)");
    }

    std::size_t face_count = 0;
    for (const auto& loop : face_indices) {
        face_count += loop.empty() ? 0 : 1;
    }
    if (face_count < 4 || merged.size() < 4) {
        return fail(result, PolyhedronError::empty,
                    "the half-spaces have no common interior (" + std::to_string(face_count) +
                        " faces, " + std::to_string(merged.size()) + " vertices remain)");
    }

    // Thickness along every face normal: a solid flatter than the tolerance is empty.
    for (std::size_t i = 0; i < dplanes.size(); ++i) {
        if (face_indices[i].empty()) {
            continue;
        }
        double depth = 0.0;
        for (const dvec3& v : merged) {
            depth = std::max(depth, -dplanes[i].signed_distance(v));
        }
        if (depth < tol) {
            return fail(result, PolyhedronError::empty,
                        "the solid is thinner than the tolerance (" + std::to_string(depth) +
                            " units) across " + plane_text(i, planes[i]));
        }
    }

    ConvexPolyhedron poly;
    poly.planes_ = std::move(normalized);
    poly.vertices_.reserve(merged.size());
    for (const dvec3& v : merged) {
        poly.vertices_.emplace_back(v);
        poly.bounds_.extend(glm::vec3(v));
    }
    poly.faces_.reserve(face_count);
    for (std::size_t i = 0; i < face_indices.size(); ++i) {
        if (face_indices[i].empty()) {
            continue;
        }
        poly.faces_.push_back(PolyhedronFace{poly.planes_[i], std::move(face_indices[i])});
    }
    // Bounding sphere: box centre, radius to the farthest vertex measured from the
    // float centre and rounded up, so float rounding never leaves a vertex outside.
    const glm::vec3 centre = poly.bounds_.center();
    double radius_sq = 0.0;
    for (const glm::vec3& v : poly.vertices_) {
        const dvec3 d = dvec3(v) - dvec3(centre);
        radius_sq = std::max(radius_sq, glm::dot(d, d));
    }
    const double radius = std::sqrt(radius_sq);
    poly.sphere_ = Sphere{centre, static_cast<float>(radius * (1.0 + 1.0e-5) + 1.0e-5)};
    return poly;
}

ConvexPolyhedron ConvexPolyhedron::from_aabb(const Aabb& box) {
    if (box.is_empty()) {
        return {};
    }
    const Plane planes[6] = {
        {{1, 0, 0}, box.max.x},   {{-1, 0, 0}, -box.min.x}, {{0, 1, 0}, box.max.y},
        {{0, -1, 0}, -box.min.y}, {{0, 0, 1}, box.max.z},   {{0, 0, -1}, -box.min.z},
    };
    PolyhedronResult result;
    return from_planes(planes, result, 1.0e-4f);
}

bool ConvexPolyhedron::contains(glm::vec3 p, float epsilon) const {
    if (vertices_.empty()) {
        return false;
    }
    for (const Plane& plane : planes_) {
        if (plane.signed_distance(p) > epsilon) {
            return false;
        }
    }
    return true;
}

} // namespace dsoc::visibility
