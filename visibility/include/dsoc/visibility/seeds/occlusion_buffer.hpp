#pragma once
// Omnidirectional software z-pyramid (hierarchical z-buffer, Greene et al. 1993)
// around one eye: six axis-aligned cube faces of face_resolution^2 texels each,
// every face with a max-pyramid. Occluders are rasterized conservatively; boxes are
// tested hierarchically. See docs/visibility.md for the conservative rules.
// A seed backend, not on the server's path (its culler covers an eye region:
// RegionOcclusionBuffer, ShaftOcclusion); dsoc-inspect's depth pictures,
// visibility_bench and the property tests use it (docs/architecture.md).

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/cube_z_pyramid.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace dsoc::visibility {

struct OcclusionBufferConfig {
    /// Texels along one side of each of the six cube faces (90 degrees each).
    /// [Units: texels] [Limit: power of two, 8..1024]
    int face_resolution = 64;
    /// At most this many occluders are rasterized per build, nearest first (by the
    /// distance to the BSP nodes' bounds). [Units: occluders] [Limit: >= 0]
    int max_occluders = 256;
    /// Occluders whose bounds are farther than this from the eye are not rasterized.
    /// [Units: world units] [Limit: > 0]
    float max_occluder_distance = 4096.0f;
    /// Boxes closer than this to the eye are always visible. [Units: world units]
    /// [Limit: > 0]
    float near_distance = 1.0f;
};

/// Every problem with the settings, in words; empty when they are usable.
[[nodiscard]] std::vector<std::string> validate(const OcclusionBufferConfig& config);

struct OcclusionBufferStats {
    int occluders_visited = 0; ///< occluders handed to add_occluder
    int occluders_written = 0; ///< of those, how many covered at least one texel
    std::int64_t texels_written = 0;
};

/// One eye's occlusion buffer. Build once per eye per tick (memory is reused across
/// builds); then test_box() any number of times. Threading: one buffer per thread;
/// test_box() is const and may run concurrently once build() has returned.
///
/// Depth is the distance along the face's axis from the eye ("view z"), in world
/// units. A level-0 texel holds a depth D such that every point seen through the
/// texel farther than D is hidden (+inf when nothing is known); level k holds the
/// max of its 4 texels of level k-1. Memory: 6 * (4/3) * face_resolution^2 floats
/// (128 KiB at 64), allocated in the constructor; build() allocates only when its
/// traversal heap outgrows its previous high-water mark.
class OcclusionBuffer {
public:
    explicit OcclusionBuffer(const OcclusionBufferConfig& config = {});

    /// begin(eye), then the BSP's occluders nearest-first within the config's budget
    /// (BspTree::traverse_nearest_first), then finish().
    void build(glm::vec3 eye, const OccluderWorld& world, const BspTree& bsp);

    /// From-region mode (extended projections, Durand et al. 2000): the buffer holds
    /// for EVERY eye in `region` (a box, e.g. the viewer's reachable region for the
    /// latency allowance). A texel is written only when the occluder covers it from
    /// all 8 region corners (hence, by convexity, from every eye in the region), at
    /// the farthest entry depth over those corners; test_box() then tests the box
    /// B - R (all vectors from an eye of R to a point of B) at its nearest depth.
    /// Occluders not provably outside the region are skipped. About 8x the
    /// rasterization cost of a point build. Occluder order/budget: nearest-first from
    /// the region's centre.
    void build_region(const Aabb& region, const OccluderWorld& world, const BspTree& bsp);

    /// Low-level building: clear for a new eye, add occluders (any order), finish
    /// (builds the pyramid). test_box() is valid only after finish().
    void begin(glm::vec3 eye);
    void begin_region(const Aabb& region);
    /// Rasterizes the convex solid { x : dot(n_i, x) <= d_i } (unit normals, at most
    /// kMaxOccluderPlanes planes; more are skipped, which is conservative).
    /// `bounds` must contain it. An occluder containing the eye (or within 1e-3 of
    /// it) writes nothing. Returns true when some texel was written.
    bool add_occluder(std::span<const Plane> planes, const Aabb& bounds);
    void finish();

    /// `occluded` only when the box is hidden from the eye (from every eye of the
    /// region, after build_region) by the rasterized occluders in every direction it
    /// spans; `visible` otherwise (may be a false positive). A box within
    /// near_distance of the eye or region (or touching it), or an empty box, is
    /// visible.
    [[nodiscard]] Visibility test_box(const Aabb& box) const;

    /// The eye (point mode) or the region's centre.
    [[nodiscard]] glm::vec3 eye() const { return eye_; }
    /// The viewer region; min == max == eye() in point mode.
    [[nodiscard]] const Aabb& region() const { return region_; }
    [[nodiscard]] const OcclusionBufferConfig& config() const { return config_; }
    [[nodiscard]] const OcclusionBufferStats& stats() const { return stats_; }
    [[nodiscard]] int levels() const { return pyramid_.levels(); }
    /// Texel of face `face` (0..5: +x, -x, +y, -y, +z, -z) at `level` (0 = finest).
    [[nodiscard]] float depth(int face, int level, int x, int y) const {
        return pyramid_.depth(face, level, x, y);
    }

    static constexpr std::size_t kMaxOccluderPlanes = 64;

private:
    struct Rect : TexelRect {
        float z_near;
    };
    /// Pixel rectangle on `face` covering the part of `rel_box` (relative to the eye)
    /// that lies in the face's frustum with view z >= min_z. False when none does.
    [[nodiscard]] bool face_rect(int face, const Aabb& rel_box, float min_z, Rect& rect) const;
    void rasterize_face(int face, const Rect& rect, std::span<const Plane> planes, const float* num,
                        std::size_t plane_count);

    OcclusionBufferConfig config_;
    glm::vec3 eye_{0.0f};
    Aabb region_{glm::vec3(0.0f), glm::vec3(0.0f)};
    bool region_mode_ = false;
    int eye_count_ = 1;
    glm::vec3 eyes_[8];
    CubeZPyramid pyramid_;
    std::vector<float> corner_u_; ///< u (or v) of corner k: -1 + 2k/N
    // Scratch for rasterization, sized once.
    std::vector<float> row_prev_, row_cur_, w_front_, w_back_;
    std::vector<float> coef_; ///< per eye: front then back (a, b, c) triples
    std::vector<float> num_;  ///< per eye: d_i - n_i.eye
    std::vector<std::pair<float, std::int32_t>> heap_;
    OcclusionBufferStats stats_;
    bool any_written_ = false;
};

} // namespace dsoc::visibility
