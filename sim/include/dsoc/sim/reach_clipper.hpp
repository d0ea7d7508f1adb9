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
// others are ignored, which is conservative. Threading: built once; clip() is const
// and safe to call from many threads.

#include "dsoc/maps/map.hpp"
#include "dsoc/sim/player_move.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <span>
#include <vector>

namespace dsoc::sim {

class ReachClipper {
public:
    ReachClipper() = default;
    /// Keeps the brushes of `brushes` that block players (solid or player clip) and
    /// are axis-aligned boxes. `move` gives the player's box and eye height.
    ReachClipper(std::span<const maps::CollisionBrush> brushes, const MoveConfig& move);

    /// `region` (a box of eye positions containing `eye`) minus the parts the
    /// player's box cannot reach from `eye`. Returns `region` unchanged when `eye`'s
    /// box already overlaps a brush (a stuck or teleported player).
    [[nodiscard]] visibility::Aabb clip(glm::vec3 eye, const visibility::Aabb& region) const;

    [[nodiscard]] std::size_t box_brush_count() const { return boxes_.size(); }

private:
    std::vector<visibility::Aabb> boxes_;
    glm::vec3 box_min_{0.0f}; ///< the player's box relative to the eye
    glm::vec3 box_max_{0.0f};
};

} // namespace dsoc::sim
