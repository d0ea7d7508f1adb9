#pragma once
// A uniform grid of cubic cells over a box: the space the baked cell visibility table
// (cell_visibility.hpp) speaks about.

#include "dsoc/visibility/geometry.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>

namespace dsoc::visibility {

/// Cells are closed boxes: a point on a face shared by two cells belongs to both, so
/// every point of the grid's box lies in at least one cell. Cell (x, y, z) spans
/// origin + cell_size * [x, x+1] x [y, y+1] x [z, z+1]; cells are numbered x fastest.
struct CellGrid {
    glm::vec3 origin{0.0f};
    float cell_size = 0.0f; ///< [Units: world units] [Limit: > 0]
    glm::ivec3 dims{0};     ///< cells per axis [Limit: >= 1 each, product < 2^31]

    /// The grid of `cell_size` cells whose box holds `bounds` (origin at bounds.min).
    [[nodiscard]] static CellGrid covering(const Aabb& bounds, float cell_size);

    [[nodiscard]] std::size_t cell_count() const {
        return static_cast<std::size_t>(dims.x) * static_cast<std::size_t>(dims.y) *
               static_cast<std::size_t>(dims.z);
    }
    [[nodiscard]] std::uint32_t index(glm::ivec3 c) const {
        return static_cast<std::uint32_t>((c.z * dims.y + c.y) * dims.x + c.x);
    }
    [[nodiscard]] glm::ivec3 coords(std::uint32_t i) const {
        const int x = static_cast<int>(i % static_cast<std::uint32_t>(dims.x));
        const std::uint32_t rest = i / static_cast<std::uint32_t>(dims.x);
        return {x, static_cast<int>(rest % static_cast<std::uint32_t>(dims.y)),
                static_cast<int>(rest / static_cast<std::uint32_t>(dims.y))};
    }
    [[nodiscard]] Aabb cell_box(glm::ivec3 c) const;
    /// The grid's whole box.
    [[nodiscard]] Aabb bounds() const;

    /// The cells a closed box touches, [lo, hi] inclusive per axis, widened by a small
    /// fraction of a cell so that float rounding at a cell face can only add cells.
    /// False (lo, hi unset) when part of the box lies outside the grid: the grid does
    /// not cover it, and no answer about it may come from the grid's cells.
    [[nodiscard]] bool range_of(const Aabb& box, glm::ivec3& lo, glm::ivec3& hi) const;
};

} // namespace dsoc::visibility
