#pragma once
// From-region occlusion: an omnidirectional hierarchical z-buffer whose answers hold
// for EVERY eye in a box region R (the eyes a client can reach within its latency
// allowance), built with extended projections (Durand, Drettakis, Thollot, Puech,
// SIGGRAPH 2000). Six projection planes, the faces of a cube of half-size D around
// R's centre; an occluder is written where it blocks the rays from every point of R
// (the intersection of its projections from R's corners), at a bound on the depth
// where those rays enter it; a box is tested with the union of its projections, at
// its nearest depth. With R a point this is the point buffer (OcclusionBuffer).
// docs/region-visibility.md has the math and why each step is conservative.

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/cube_z_pyramid.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace dsoc::visibility {

struct RegionOcclusionBufferConfig {
    /// Texels along one side of each of the six cube faces.
    /// [Units: texels] [Limit: power of two, 8..1024]
    int face_resolution = 64;
    /// At most this many occluders are rasterized per build, nearest to the region's
    /// centre first (by the distance to the BSP nodes' bounds). [Units: occluders]
    /// [Limit: >= 0]
    int max_occluders = 256;
    /// Occluders whose bounds are farther than this from the region are not
    /// rasterized. [Units: world units] [Limit: > 0]
    float max_occluder_distance = 4096.0f;
    /// Half-size D of the projection cube around the region's centre: rays are
    /// binned by where they leave it. An occluder at distance d along a face axis
    /// loses about 2 * h * |1/D - 1/d| of face coordinate to the region's parallax
    /// (h the region's half-extent; nothing at d = D), so D should sit among the
    /// distances of the occluders that matter. 1024 culls 2.7x more than 256 on the
    /// test worlds (docs/region-visibility.md). A build uses
    /// max(projection_distance, 1.25 * half-diagonal of the region + 1) so the
    /// region stays strictly inside the cube. [Units: world units] [Limit: > 0, finite]
    float projection_distance = 1024.0f;
};

/// Every problem with the settings, in words; empty when they are usable.
[[nodiscard]] std::vector<std::string> validate(const RegionOcclusionBufferConfig& config);

struct RegionOcclusionBufferStats {
    int occluders_visited = 0;          ///< occluders handed to add_occluder
    int occluders_skipped_region = 0;   ///< of those, skipped: they touch the region
    int occluders_written = 0;          ///< of those, how many covered at least one texel
    std::int64_t texels_written = 0;    ///< level-0 texels lowered
    std::int64_t corners_evaluated = 0; ///< texel-corner x region-corner ray tests
    float projection_distance = 0.0f;   ///< D actually used by the last build
};

/// One region's occlusion buffer. Build once per region (memory is reused across
/// builds, nothing is allocated after construction except the BSP traversal's heap
/// on its first growth); then test_box() any number of times.
/// Threading: build() and add_occluder() mutate; test_box(), depth() and the other
/// const members may run concurrently once build()/finish() has returned.
///
/// Depth is the coordinate along the face's axis relative to the region's centre
/// (oriented: for the -x face it is c.x - x), in world units. A level-0 texel holds
/// a depth z such that, for every eye p of the region and every ray from p leaving
/// the projection cube through that texel, the ray enters an occluder's interior at
/// depth <= z; +inf when no such occluder was found. Level k holds the max of 4
/// texels of level k-1.
class RegionOcclusionBuffer {
public:
    explicit RegionOcclusionBuffer(const RegionOcclusionBufferConfig& config = {});

    /// begin(eye_region), then the BSP's occluders nearest-first from the region's
    /// centre within the config's budget and distance, then finish().
    void build(const Aabb& eye_region, const OccluderWorld& world, const BspTree& bsp);

    /// Low-level building: clear for a new region, add occluders (any order), finish
    /// (builds the pyramid). test_box() is valid only after finish(). An empty region
    /// makes a buffer that answers `visible` to everything.
    void begin(const Aabb& eye_region);
    /// Rasterizes the convex solid { x : dot(n_i, x) <= d_i } (unit normals, 4 to
    /// kMaxOccluderPlanes planes, else skipped: conservative). `bounds` must contain
    /// it. An occluder that intersects the region, or comes within 1 unit of it,
    /// writes nothing. Returns true when some texel was lowered.
    bool add_occluder(std::span<const Plane> planes, const Aabb& bounds);
    void finish();

    /// `occluded` only when the box is hidden from EVERY point of the region: every
    /// segment from any point of the region to any point of the box passes through
    /// the interior of some rasterized occluder (up to float margins, which all err
    /// towards `visible`). `visible` otherwise, which may be a false positive. A box
    /// that overlaps the region or comes within 1 unit of it, an empty box, and any
    /// box before the first write, are `visible`.
    [[nodiscard]] Visibility test_box(const Aabb& box) const;

    /// The region of the last begin()/build().
    [[nodiscard]] const Aabb& region() const { return region_; }
    [[nodiscard]] const RegionOcclusionBufferConfig& config() const { return config_; }
    [[nodiscard]] const RegionOcclusionBufferStats& stats() const { return stats_; }
    [[nodiscard]] int levels() const { return pyramid_.levels(); }
    /// Texel of face `face` (0..5: +x, -x, +y, -y, +z, -z) at `level` (0 = finest);
    /// x runs along the face's first lateral axis (y for the x faces, else x), y along
    /// the second (z for the x and y faces, else y), both increasing with the world
    /// coordinate.
    [[nodiscard]] float depth(int face, int level, int x, int y) const {
        return pyramid_.depth(face, level, x, y);
    }

    static constexpr std::size_t kMaxOccluderPlanes = 32;
    static constexpr int kMaxRegionCorners = 8;

private:
    using Rect = TexelRect;
    /// Smallest forward offset (along a face's axis) from an eye of the region to a
    /// point `distance` away from it on a ray that leaves by that face.
    [[nodiscard]] float min_forward_distance(float distance) const;
    /// Converts a face-coordinate interval to a texel range; false when it is empty.
    [[nodiscard]] bool texel_range(float lo, float hi, int& first, int& last) const;
    void rasterize_face(int face, const Rect& rect, std::span<const Plane> planes,
                        const double* plane_offset, float depth_near, float depth_far);

    RegionOcclusionBufferConfig config_;
    Aabb region_;
    glm::vec3 center_{0.0f};
    glm::vec3 half_{0.0f};
    float distance_ = 0.0f; ///< D of the current build
    /// Region corners relative to the centre (deduplicated: 1, 2, 4 or 8).
    glm::vec3 corner_[kMaxRegionCorners];
    int corner_count_ = 0;
    CubeZPyramid pyramid_;
    std::vector<float> grid_s_; ///< face coordinate of texel corner k: -1 + 2k/N
    // Scratch for rasterization, sized once.
    std::vector<float> wf_, wb_, entry_prev_, entry_cur_;
    std::vector<std::uint8_t> near_prev_, near_cur_, far_prev_, far_cur_;
    std::vector<std::pair<float, std::int32_t>> heap_;
    RegionOcclusionBufferStats stats_;
    bool valid_region_ = false;
    bool any_written_ = false;
};

} // namespace dsoc::visibility
