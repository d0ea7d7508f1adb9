#pragma once
// Occlusion beams (the second backend of the BSP seed): from one eye, each near
// occluder casts a beam: the convex region behind it inside its silhouette cone.
// BSP nodes whose containment sphere lies inside a beam are skipped wholesale.
// Beams do not fuse: an item hidden only by two occluders together stays visible.
// It exists to compare honestly against the z-pyramid (OcclusionBuffer): not on the
// server's path; visibility_bench and the property tests use it (docs/architecture.md).

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>
#include <vector>

namespace dsoc::visibility {

struct OcclusionBeamsConfig {
    /// At most this many beams per eye, nearest occluders first
    /// (BspTree::traverse_nearest_first; nodes whose containment sphere is inside a
    /// beam are skipped).
    /// [Units: beams] [Limit: >= 0]
    int max_beams = 64;
    /// Occluders farther than this make no beam. [Units: world units] [Limit: > 0]
    float max_occluder_distance = 4096.0f;
    /// Occluders whose bounding sphere subtends less than this angle (radius over
    /// distance) make no beam: they would hide little. [Units: radians] [Limit: >= 0]
    float min_angular_radius = 0.02f;
};

struct OcclusionBeamsStats {
    int beams = 0;
    int nodes_culled = 0; ///< BSP subtrees skipped because a beam contained them
};

/// One eye's beams. Build once per eye (memory reused), then test boxes/spheres.
/// Threading: one instance per thread; tests are const.
class OcclusionBeams {
public:
    explicit OcclusionBeams(const OcclusionBeamsConfig& config = {}) : config_(config) {}

    void build(glm::vec3 eye, const OccluderWorld& world, const BspTree& bsp);

    /// `occluded` when the whole box lies inside one beam, strictly (by a margin of
    /// 1e-4 of its distance + 1e-3 + the vertex-rounding slack): every segment from
    /// the eye to it crosses that occluder's interior. `visible` otherwise (may be a
    /// false positive).
    [[nodiscard]] Visibility test_box(const Aabb& box) const;
    [[nodiscard]] Visibility test_sphere(const Sphere& sphere) const;

    [[nodiscard]] const OcclusionBeamsStats& stats() const { return stats_; }
    [[nodiscard]] glm::vec3 eye() const { return eye_; }

private:
    struct Beam {
        std::uint32_t first_plane, plane_count;
        /// Extra margin per unit of distance from the eye, for the float rounding
        /// of the vertices the silhouette planes go through.
        float angular_slack;
    };
    /// Adds the beam of occluder `id`; false when it cannot make one.
    bool add_beam(const OccluderWorld& world, OccluderId id);
    template <class InsideFn>
    [[nodiscard]] bool inside_some_beam(InsideFn&& inside) const;

    OcclusionBeamsConfig config_;
    glm::vec3 eye_{0.0f};
    std::vector<Beam> beams_;
    /// All beams' planes, relative to the eye (the eye is the origin); inside is
    /// signed_distance <= 0.
    std::vector<Plane> planes_;
    std::vector<std::uint8_t> front_scratch_;
    std::vector<double> offset_scratch_;
    std::vector<std::pair<float, std::int32_t>> heap_;
    OcclusionBeamsStats stats_;
};

} // namespace dsoc::visibility
