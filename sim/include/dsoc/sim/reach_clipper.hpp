#pragma once
// Shrinks a box of reachable eye positions using walls the player's box cannot pass.
//
// The eye of a walking player is never closer to a brush than its box allows, and the
// box never enters a brush. If an axis-aligned face of a box-shaped brush covers the
// whole cross-section of the region the player's box can sweep, the box cannot get
// past that face while staying in the region, so the eye stays on its side:
// `eye.x <= face.x - box_max.x` for a face ahead in +x, and so on. Clipping the eye
// region this way keeps it conservative (it still contains every eye the player can
// reach without teleporting) and lets the culler use the walls right next to the
// player, which a region overlapping them could not.
//
// Only brushes that are axis-aligned boxes take part (most Quake 3 walls and floors);
// others are ignored, which is conservative.
//
// Falls: the mover gains downward speed beyond gravity only while standing on
// walkable sloped ground (player_move.hpp), and the motion limits assume the steepest
// walkable slope everywhere (fall_speed_floor). When no sloped walkable face lies
// within the region the player's box can sweep, the fall is gravity's alone, and the
// region's floor is raised to it (clip() with an EyeReach that says how the region
// was made).
//
// Threading: built once; clip() is const and safe to call from many threads.

#include "dsoc/maps/map.hpp"
#include "dsoc/sim/player_move.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/interest_manager.hpp"
#include <glm/vec2.hpp>

#include <span>
#include <vector>

namespace dsoc::sim {

class ReachClipper {
public:
    /// The default column of the wall index. [Units: world units]
    static constexpr float kColumnSize = 128.0f;

    ReachClipper() = default;
    /// Keeps the brushes of `brushes` that block players (solid or player clip) and
    /// are axis-aligned boxes. `move` gives the player's box and eye height.
    /// `column_size` is the xy grid that finds the walls near a region (a few walls
    /// near it instead of all of them; the answers are the same for any size).
    ReachClipper(std::span<const maps::CollisionBrush> brushes, const MoveConfig& move,
                 float column_size = kColumnSize);

    /// `region` (a box of eye positions containing `eye`) minus the parts the
    /// player's box cannot reach from `eye`. Returns `region` unchanged when `eye`'s
    /// box already overlaps a brush (a stuck or teleported player). When `reach` says
    /// the region is reachable_box(eye, *reach.limits, reach.seconds, 1,
    /// reach.down_velocity) (limits with gravity and a known downward speed), its floor
    /// is raised to the fall with the walk-down speed of the slopes in reach only.
    [[nodiscard]] visibility::Aabb clip(glm::vec3 eye, const visibility::Aabb& region,
                                        const visibility::EyeReach& reach = {}) const;

    /// The most downward speed walking can reach (player_move.hpp: walk_down_speed of
    /// the steepest walkable sloped face) for an eye anywhere in `eye_region`; 0 when
    /// no sloped walkable face is within the player's box's reach. [Units: world units/s]
    [[nodiscard]] float walk_down_speed_within(const visibility::Aabb& eye_region) const;

    [[nodiscard]] std::size_t box_brush_count() const { return boxes_.size(); }
    [[nodiscard]] std::size_t slope_count() const { return slopes_.size(); }

private:
    /// A brush with walkable sloped faces: its bounds hold every such face.
    struct Slope {
        visibility::Aabb bounds;
        float walk_down_speed; ///< of its steepest walkable face [Units: world units/s]
    };

    [[nodiscard]] visibility::Aabb clip_to_walls(glm::vec3 eye,
                                                 const visibility::Aabb& region) const;

    static constexpr float kMaxColumnsPerAxis = 256.0f;
    struct ColumnRange {
        int x0, x1, y0, y1; ///< inclusive
    };
    /// Builds the columns, each at least `column_size` (at most kMaxColumnsPerAxis a side).
    void index_boxes(float column_size);
    [[nodiscard]] ColumnRange columns_of(const visibility::Aabb& area) const;
    /// Calls `visit(box)` for every box of boxes_ whose xy bounds may overlap `area`'s
    /// (some more than once: every visit here is idempotent).
    template <class Visit>
    void for_boxes_near(const visibility::Aabb& area, Visit&& visit) const;

    std::vector<visibility::Aabb> boxes_;
    /// boxes_ by column of a uniform xy grid (CSR): a box is listed in every column its
    /// bounds overlap, so a small region looks at the walls near it only.
    glm::vec2 columns_origin_{0.0f};
    float column_size_ = 1.0f; ///< [Units: world units]
    int columns_x_ = 0;
    int columns_y_ = 0;
    std::vector<std::uint32_t> column_start_;
    std::vector<std::uint32_t> column_boxes_;
    std::vector<Slope> slopes_;
    glm::vec3 box_min_{0.0f}; ///< the player's box relative to the eye
    glm::vec3 box_max_{0.0f};
};

} // namespace dsoc::sim
