#pragma once
// The unions of a baked table's rows (cell_visibility.hpp) over blocks of 2 x 2 x 2
// cells, one block at every cell of the grid but the last on each axis (its "anchor",
// the block's lowest corner). A region's union of rows, which BakedRegionVisibility
// builds for a client whenever the cells of its eye region change, then takes about an
// eighth as many rows. Blocks may overlap: a row ORed twice changes nothing, so a range
// of at least two cells on every axis is the union of the blocks inside it, exactly.
// Derived from the table where it is loaded; read-only afterwards, shared by threads.

#include "dsoc/visibility/cell_visibility.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::visibility {

class CellBlockUnions {
public:
    /// The unions of `table`'s rows (compressed or dense) over every block.
    explicit CellBlockUnions(const CellVisibilityTable& table);

    /// Cells on an axis of a range or_range_into() answers for, at the most.
    static constexpr int kMaxRangeCells = 64;
    /// Whether or_range_into() answers for the cell range [lo, hi] (inclusive): two
    /// cells or more on every axis, kMaxRangeCells at the most.
    [[nodiscard]] static bool covers(glm::ivec3 lo, glm::ivec3 hi) {
        const glm::ivec3 n = hi - lo + 1;
        return n.x >= 2 && n.y >= 2 && n.z >= 2 && n.x <= kMaxRangeCells && n.y <= kMaxRangeCells &&
               n.z <= kMaxRangeCells;
    }
    /// ORs into `out` (words_per_row() words of the table) the rows of every open cell
    /// in the cell range [lo, hi], which lies in the grid and covers() holds for: the
    /// same bits as ORing the table's rows of those cells.
    void or_range_into(glm::ivec3 lo, glm::ivec3 hi, std::span<std::uint64_t> out) const;

    /// Blocks with an open cell (each holds a union).
    [[nodiscard]] std::size_t block_count() const { return literal_start_.size() - 1; }
    /// Bytes of the unions and their index held in memory.
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    glm::ivec3 anchors_{0}; ///< anchors per axis: the grid's cells less one
    std::size_t bits_ = 0;  ///< bits of a row: the table's open cells
    std::size_t words_ = 0;
    std::size_t class_words_ = 0;
    /// Per anchor (x fastest): its block's union, or -1 when the block has no open cell.
    std::vector<std::int32_t> union_of_;
    /// The unions coded as the table's compressed rows (row_codes.hpp).
    std::vector<std::uint64_t> classes_;
    std::vector<std::uint64_t> literal_start_;
    std::vector<std::uint64_t> literals_;
};

} // namespace dsoc::visibility
