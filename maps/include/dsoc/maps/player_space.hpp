#pragma once
// Where a walking player's box and eye region can be: the space above walkable ground.
// A baked cell table need only answer there; the cells it leaves out are its
// "uncovered" cells (cell_visibility.hpp), about which it answers nothing, so a player
// who is elsewhere (falling far, thrown by a jump pad) is never culled by guess.

#include "dsoc/maps/map.hpp"
#include "dsoc/visibility/cell_grid.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::maps {

/// The union of one box per walkable face of a collision brush (a face whose outward
/// normal has z >= min_walk_normal_z): the face's bounds, raised by `height` and
/// widened by `margin` on both horizontal axes. An over-approximation of where a
/// walker stands, steps, jumps and looks from, by construction of the caller's
/// numbers (sim::player_space()).
struct PlayerSpace {
    /// [Limit: 0 .. 1]
    float min_walk_normal_z = 0.7f;
    /// Above each walkable face's highest point. [Units: world units] [Limit: 1 .. 4096]
    float height = 0.0f;
    /// Horizontally, on every side of each face. [Units: world units] [Limit: 0 .. 4096]
    float margin = 0.0f;

    friend bool operator==(const PlayerSpace&, const PlayerSpace&) = default;
};

/// Every problem with the settings, in words; empty when they are usable.
[[nodiscard]] std::vector<std::string> validate(const PlayerSpace& space);

/// The boxes whose union is `space` on `map`, one per walkable face.
[[nodiscard]] std::vector<visibility::Aabb> player_space_boxes(const Map& map,
                                                               const PlayerSpace& space);

/// One byte per cell of `grid`: 1 where the cell meets one of `boxes` (closed boxes, so
/// a cell that only touches one counts), 0 elsewhere.
[[nodiscard]] std::vector<std::uint8_t> cells_meeting(const visibility::CellGrid& grid,
                                                      const std::vector<visibility::Aabb>& boxes);

} // namespace dsoc::maps
