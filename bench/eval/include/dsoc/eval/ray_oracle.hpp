#pragma once
// The evaluation's independent visibility oracle: Embree ray casts against the
// occluders' triangles (and the map's opaque curved surfaces, which block sight in the
// game though no culler uses them), sharing no code with dsoc's rasterizer. An entity is visible
// from an eye when any ray from the eye to a dense set of sample points on its box is
// unblocked (the spec's test, sampled: a `visible` answer is a certificate, an
// `occluded` one can miss a gap narrower than the sample spacing).
//
// Touching a face is not blocking (replication-trace spec): every ray is shortened at
// both ends by kEndTrim world units, a fixed length, so that a wall crossed within a
// unit of an entity far away still blocks (a trim in proportion to the length let a
// ray 1,175 units long pass under a wall's corner 0.9 units in front of a box).
//
// Threading: built once; every const member may run concurrently (Embree's
// rtcOccluded on a committed scene is thread-safe).

#include "dsoc/visibility/convex_polyhedron.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::eval {

class RayOracle {
public:
    /// Length dropped at each end of a ray, so that an endpoint on a face (a box
    /// resting on a floor or against a wall) does not count as blocked. Far above the
    /// float spacing of map coordinates (under 0.001 below 8,192 units) and the brush
    /// tolerance (1/64), far below the 0.125 units players keep from walls.
    /// [Units: world units]
    static constexpr float kEndTrim = 1.0f / 32.0f;

    /// Fan-triangulates every face of every non-empty polyhedron; `triangles` (three
    /// points each) block sight too: surfaces that the game draws opaque and that are
    /// not occluders, such as a Quake 3 map's curved patches (Map::opaque_patches).
    explicit RayOracle(std::span<const visibility::ConvexPolyhedron> occluders,
                       std::span<const glm::vec3> triangles = {});
    ~RayOracle();
    RayOracle(const RayOracle&) = delete;
    RayOracle& operator=(const RayOracle&) = delete;

    /// True when some occluder triangle crosses the segment from `from` to `to`
    /// (shortened at both ends).
    [[nodiscard]] bool segment_blocked(glm::vec3 from, glm::vec3 to) const;

    /// True when any of `points` can be seen from `eye`. Casts 16 rays at a time
    /// and stops at the first unblocked one.
    [[nodiscard]] bool any_visible(glm::vec3 eye, std::span<const glm::vec3> points) const;

    /// The box's samples: a `grid` x `grid` lattice on each face (grid >= 2: corners
    /// and edges included, shared points once), centre first, then the 8 corners, then
    /// the rest (so a visible box is usually confirmed by the first rays).
    static void box_samples(const visibility::Aabb& box, int grid, std::vector<glm::vec3>& out);

    /// The samples that matter from `eye`: the centre, then a `grid` x `grid` lattice
    /// on each face turned toward the eye (shared edge points once). A segment from
    /// the eye to a point of a face turned away enters the box through a face turned
    /// toward it, and its part up to there is unblocked whenever the whole is: so a
    /// box with a visible point always has a visible point on its front faces, and
    /// testing those alone loses nothing but sample placement.
    static void front_samples(glm::vec3 eye, const visibility::Aabb& box, int grid,
                              std::vector<glm::vec3>& out);

    /// Visible when the box contains the eye or any front sample (front_samples with
    /// `grid`) is seen from it.
    [[nodiscard]] bool box_visible(glm::vec3 eye, const visibility::Aabb& box, int grid) const;

    [[nodiscard]] std::size_t triangle_count() const { return triangles_; }

private:
    void* device_ = nullptr; // RTCDevice
    void* scene_ = nullptr;  // RTCScene
    std::size_t triangles_ = 0;
};

} // namespace dsoc::eval
