#pragma once
// Swept axis-aligned boxes against convex brushes, the Quake 3 way: each brush plane
// is pushed out by the box's support distance and a point is traced against the
// expanded planes. Exact for brushes whose bevel planes are present (Quake 3 BSP
// brushes carry the compiler's axial and edge bevels; dsoc::maps adds axial bevels to
// every brush); without edge bevels it is conservative near slanted edges (blocks a
// little early, never lets a box through).
//
// Threading: built once; every const member is safe to call from many threads.

#include "dsoc/maps/map.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::sim {

/// A trace stops this far in front of the surface it hits, so that the next trace
/// does not start inside. [Units: world units]
inline constexpr float kSurfaceClipEpsilon = 0.125f;

struct BoxTrace {
    /// Share of the way from start to end that is free, in [0, 1]; 1 = nothing hit.
    float fraction = 1.0f;
    glm::vec3 end_position{0.0f};
    /// The surface hit (valid when fraction < 1): normal points away from the brush.
    glm::vec3 hit_normal{0.0f};
    /// The box at `start` already overlaps a brush.
    bool start_solid = false;
    /// The whole trace is inside a brush (then fraction = 0).
    bool all_solid = false;
    /// Index of the brush hit, or -1.
    std::int32_t brush = -1;
};

class CollisionWorld {
public:
    CollisionWorld() = default;
    /// Keeps the brushes whose contents intersect `contents_mask`. Brushes must have
    /// finite planes and non-empty bounds (as dsoc::maps produces them).
    explicit CollisionWorld(std::span<const maps::CollisionBrush> brushes,
                            std::uint32_t contents_mask = maps::contents_solid |
                                                          maps::contents_player_clip);

    /// Sweeps the box [origin + mins, origin + maxs] from `start` to `end`.
    /// Precondition: mins <= maxs on every axis, all inputs finite.
    [[nodiscard]] BoxTrace trace_box(glm::vec3 start, glm::vec3 end, glm::vec3 mins,
                                     glm::vec3 maxs) const;

    /// True when the box at `origin`, shrunk by `tolerance` on every side, overlaps a
    /// brush's interior.
    [[nodiscard]] bool box_in_solid(glm::vec3 origin, glm::vec3 mins, glm::vec3 maxs,
                                    float tolerance = 0.0f) const;

    /// Union of the brushes' bounds.
    [[nodiscard]] const visibility::Aabb& bounds() const { return bounds_; }
    [[nodiscard]] std::size_t brush_count() const { return brushes_.size(); }

private:
    struct Brush {
        std::uint32_t first_plane = 0;
        std::uint32_t plane_count = 0;
        visibility::Aabb bounds;
        std::int32_t cell_min[3] = {0, 0, 0}; ///< first grid cell the brush is listed in
    };

    void build_grid();
    /// Grid cell along `axis` holding `value`, clamped to the grid.
    [[nodiscard]] std::int32_t cell_coordinate(float value, int axis) const;
    void clip_brush(std::uint32_t index, glm::vec3 start, glm::vec3 end, glm::vec3 mins,
                    glm::vec3 maxs, BoxTrace& trace) const;
    template <class Visit>
    void for_each_candidate(const visibility::Aabb& query, Visit&& visit) const;

    std::vector<visibility::Plane> planes_;
    std::vector<Brush> brushes_;
    visibility::Aabb bounds_;
    // Uniform grid over bounds_: cell (x, y, z) lists the brushes overlapping it in
    // cell_brushes_[cell_start_[c] .. cell_start_[c + 1]).
    float cell_size_ = 128.0f;
    std::int32_t dims_[3] = {0, 0, 0};
    std::vector<std::uint32_t> cell_start_;
    std::vector<std::uint32_t> cell_brushes_;
};

} // namespace dsoc::sim
