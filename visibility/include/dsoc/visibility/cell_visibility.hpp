#pragma once
// A baked cell-to-cell visibility table: for every pair of open cells of a grid,
// whether anything in one may be seen from anywhere in the other.
//
// Conservative meaning: a clear bit (a, b) is a proof that every segment from a point
// of cell a to a point of cell b passes through the interior of some occluder (or of
// the compiler's PVS, where the bake used it); a set bit proves nothing. Cells whose
// box lies inside one occluder's interior are "solid": no eye and no point of an
// entity's box that can be seen lies in them, so they have no row and no column.
// The table is symmetric (visibility of segments is).

#include "dsoc/visibility/cell_grid.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::visibility {

/// Index of an open cell in a CellVisibilityTable (0 .. open_count()-1).
using OpenCell = std::int32_t;
inline constexpr OpenCell kSolidCell = -1;

class CellVisibilityTable {
public:
    CellVisibilityTable() = default;
    /// An all-hidden table over `grid` whose open cells are `open` (grid indexes,
    /// strictly increasing).
    CellVisibilityTable(const CellGrid& grid, std::vector<std::uint32_t> open);

    [[nodiscard]] const CellGrid& grid() const { return grid_; }
    [[nodiscard]] std::size_t open_count() const { return open_.size(); }
    /// Grid index of each open cell, increasing.
    [[nodiscard]] const std::vector<std::uint32_t>& open_cells() const { return open_; }
    /// The open cell at grid index `cell`, or kSolidCell.
    [[nodiscard]] OpenCell open_index(std::uint32_t cell) const { return open_of_[cell]; }
    [[nodiscard]] std::size_t words_per_row() const { return words_per_row_; }

    /// Row `from`: bit t set when open cell t may be seen from open cell `from`.
    [[nodiscard]] std::span<const std::uint64_t> row(OpenCell from) const {
        return {bits_.data() + static_cast<std::size_t>(from) * words_per_row_, words_per_row_};
    }
    [[nodiscard]] bool may_see(OpenCell from, OpenCell to) const {
        return (row(from)[static_cast<std::size_t>(to) >> 6] >> (to & 63) & 1u) != 0;
    }
    /// Sets (a, b) and (b, a) to "may see"; several threads may write at once.
    void set_visible_atomic(OpenCell a, OpenCell b);

    /// Every row, open_count() * words_per_row() words (for storage).
    [[nodiscard]] std::span<const std::uint64_t> words() const { return bits_; }
    [[nodiscard]] std::span<std::uint64_t> words() { return bits_; }

    /// The open cells a closed box touches, as runs of open-cell indexes: pairs
    /// (first, end) appended to `out` (cleared first), one run per row of the box's
    /// cells at most (open cells are numbered in grid order, so the open cells of one
    /// row are consecutive), adjacent runs joined. False when the grid does not cover
    /// the whole box, or when every cell it touches is solid: then the table must not
    /// answer for it.
    bool open_runs_of(const Aabb& box, std::vector<std::int32_t>& out) const;

    /// Pairs (ordered, self pairs included) whose bit is clear, i.e. proven hidden.
    [[nodiscard]] std::uint64_t hidden_pairs() const;
    /// Bytes of the rows and indexes held in memory.
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    CellGrid grid_;
    std::vector<std::uint32_t> open_;
    std::vector<OpenCell> open_of_;
    /// Open cells with a grid index below i, for i in 0 .. cell_count().
    std::vector<std::int32_t> open_before_;
    std::size_t words_per_row_ = 0;
    std::vector<std::uint64_t> bits_;
};

} // namespace dsoc::visibility
