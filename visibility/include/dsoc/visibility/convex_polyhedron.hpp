#pragma once
// A convex polyhedron (a brush) given as an intersection of half-spaces, with its
// vertices, faces, bounds and bounding sphere derived robustly.

#include "dsoc/visibility/geometry.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace dsoc::visibility {

/// One face: the plane it lies on and its vertices as indexes into
/// ConvexPolyhedron::vertices(), counter-clockwise seen from outside.
struct PolyhedronFace {
    Plane plane;
    std::vector<std::uint32_t> vertex_indices;
};

/// Why a set of planes does not make a usable polyhedron.
enum class PolyhedronError : std::uint8_t {
    none,
    too_few_planes,   ///< fewer than 4 planes
    non_finite_plane, ///< a NaN/Inf component or a zero normal
    unbounded,        ///< the half-spaces do not enclose a bounded region
    empty, ///< the half-spaces have no common interior (or it is flatter than the tolerance)
};

/// Readable name of an error, e.g. "unbounded". Static storage.
const char* to_string(PolyhedronError error) noexcept;

class ConvexPolyhedron;

/// Result of ConvexPolyhedron::from_planes: either a polyhedron or an error with a
/// human-readable detail (which plane, what is wrong).
struct PolyhedronResult {
    PolyhedronError error = PolyhedronError::none;
    std::string detail;
    [[nodiscard]] bool ok() const { return error == PolyhedronError::none; }
};

/// A value type: owns its planes, vertices and faces; immutable once made (by
/// from_planes() or from_aabb()), so const members may run concurrently. Used as an
/// occluder it must be opaque everywhere inside: culling trusts all of its interior.
class ConvexPolyhedron {
public:
    ConvexPolyhedron() = default;

    /// Builds the polyhedron { x : dot(n_i, x) <= d_i for all i }. Normals need not
    /// be unit length (they are normalized); redundant planes (touching the solid
    /// in fewer than 3 vertices) are dropped from faces() but kept in planes().
    /// `tolerance` (world units) merges near-coincident vertices; a region thinner
    /// than it in any direction is reported as `empty`. Never throws on bad input:
    /// the error comes back in `result` and the returned polyhedron is then empty.
    [[nodiscard]] static ConvexPolyhedron from_planes(std::span<const Plane> planes,
                                                      PolyhedronResult& result,
                                                      float tolerance = 1.0f / 64.0f);

    /// An axis-aligned box as a polyhedron (6 planes).
    [[nodiscard]] static ConvexPolyhedron from_aabb(const Aabb& box);

    [[nodiscard]] bool is_empty() const { return vertices_.empty(); }
    [[nodiscard]] const std::vector<Plane>& planes() const { return planes_; }
    [[nodiscard]] const std::vector<glm::vec3>& vertices() const { return vertices_; }
    [[nodiscard]] const std::vector<PolyhedronFace>& faces() const { return faces_; }
    [[nodiscard]] const Aabb& bounds() const { return bounds_; }
    /// A sphere containing every vertex (not necessarily minimal).
    [[nodiscard]] const Sphere& bounding_sphere() const { return sphere_; }

    /// True when `p` is inside or on the boundary (within `epsilon`).
    [[nodiscard]] bool contains(glm::vec3 p, float epsilon = 0.0f) const;

private:
    std::vector<Plane> planes_;
    std::vector<glm::vec3> vertices_;
    std::vector<PolyhedronFace> faces_;
    Aabb bounds_;
    Sphere sphere_;
};

} // namespace dsoc::visibility
