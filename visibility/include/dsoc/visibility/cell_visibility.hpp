#pragma once
// A baked cell-to-cell visibility table: for every pair of open cells of a grid,
// whether anything in one may be seen from anywhere in the other.
//
// Conservative meaning: a clear bit (a, b) is a proof that every segment from a point
// of cell a to a point of cell b passes through the interior of some occluder (or of
// the compiler's PVS, where the bake used it); a set bit proves nothing. Cells whose
// box lies inside one occluder's interior are "solid": no eye and no point of an
// entity's box that can be seen lies in them, so they have no row and no column.
// Cells the bake was told no player can be in are "uncovered": they have no row and
// no column either, but unlike solid cells they may hold an eye or a visible point, so
// the table answers nothing about a region or box that touches one.
// The table is symmetric (visibility of segments is). Rows are dense while a bake or
// the file reader fills them, then compressed for use.

#include "dsoc/visibility/cell_grid.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::visibility {

/// Index of an open cell in a CellVisibilityTable (0 .. open_count()-1).
using OpenCell = std::int32_t;
inline constexpr OpenCell kSolidCell = -1;
inline constexpr OpenCell kUncoveredCell = -2;

/// Open cells are numbered in block order: the grid is cut into blocks of
/// kTableBlockCells^3 cells (blocks in grid order, x fastest), and the open cells of a
/// block get consecutive numbers (in grid order within the block). A row's 64-bit words
/// then speak about compact pieces of space, so that most are all-hidden or
/// all-visible, which the compressed rows store in two bits.
inline constexpr int kTableBlockCells = 4;

class CellVisibilityTable {
public:
    /// dense: all-hidden dense rows, which set_visible_atomic() and words() may write
    /// until compress(); none: no rows yet (adopt_compressed() brings them).
    enum class Rows { dense, none };

    CellVisibilityTable() = default;
    /// A table over `grid` whose open cells are the grid indexes `open` (distinct, any
    /// order: they are numbered in block order) and whose uncovered cells are
    /// `uncovered` (distinct, none of them open); every other cell is solid.
    CellVisibilityTable(const CellGrid& grid, std::vector<std::uint32_t> open,
                        std::vector<std::uint32_t> uncovered = {}, Rows rows = Rows::dense);

    [[nodiscard]] const CellGrid& grid() const { return grid_; }
    [[nodiscard]] std::size_t open_count() const { return open_.size(); }
    /// Grid index of each open cell, in block order.
    [[nodiscard]] const std::vector<std::uint32_t>& open_cells() const { return open_; }
    /// Grid index of each uncovered cell, increasing.
    [[nodiscard]] const std::vector<std::uint32_t>& uncovered_cells() const { return uncovered_; }
    /// The open cell at grid index `cell`, or kSolidCell, or kUncoveredCell.
    [[nodiscard]] OpenCell open_index(std::uint32_t cell) const { return open_of_[cell]; }
    /// Position of grid cell `cell` in block order (open cells are numbered by it).
    [[nodiscard]] std::uint64_t block_rank(std::uint32_t cell) const;
    [[nodiscard]] std::size_t words_per_row() const { return words_per_row_; }

    /// Whether anything in open cell `to` may be seen from open cell `from`.
    [[nodiscard]] bool may_see(OpenCell from, OpenCell to) const;
    /// ORs row `from` (bit t: open cell t may be seen from `from`) into `out`, which
    /// holds words_per_row() words with no bit set past the last open cell.
    void or_row_into(OpenCell from, std::span<std::uint64_t> out) const;

    /// Sets (a, b) and (b, a) to "may see"; several threads may write at once. Dense
    /// rows only (before compress()).
    void set_visible_atomic(OpenCell a, OpenCell b);
    /// The dense rows, open_count() * words_per_row() words, row by row (empty once
    /// compressed).
    [[nodiscard]] std::span<const std::uint64_t> words() const { return bits_; }
    [[nodiscard]] std::span<std::uint64_t> words() { return bits_; }

    /// Replaces the dense rows by compressed ones (read-only from then on): each word
    /// of a row is stored as two bits (all hidden, all visible, or a literal) plus the
    /// literal words. Same answers.
    void compress();
    [[nodiscard]] bool compressed() const { return !literal_start_.empty(); }

    /// The compressed rows (for storage): per row class_words_per_row() words of 2-bit
    /// codes, word w of the row at bits 2(w % 32) of class word w / 32 (0: all hidden,
    /// 1: all visible, 2: literal); and the literal words, row by row, in word order.
    [[nodiscard]] std::size_t class_words_per_row() const { return (words_per_row_ + 31) / 32; }
    [[nodiscard]] std::span<const std::uint64_t> classes() const { return classes_; }
    [[nodiscard]] std::span<const std::uint64_t> literals() const { return literals_; }
    /// Takes compressed rows read from storage, in place of the dense ones, after
    /// checking every rule compress() follows (codes 0..2 and none past the row's
    /// words; as many literals as literal codes; no literal all hidden, all visible or
    /// with bits past the last open cell) and that every open cell sees itself. On a
    /// problem, returns it in words and leaves the table as it was.
    [[nodiscard]] std::optional<std::string> adopt_compressed(std::vector<std::uint64_t> classes,
                                                              std::vector<std::uint64_t> literals);

    /// The open cells a closed box touches, as runs of open-cell indexes: pairs
    /// (first, end) appended to `out` (cleared first), sorted, touching runs joined
    /// (the open cells of one row of a block are consecutive). False when the grid
    /// does not cover the whole box, when it touches an uncovered cell, or when every
    /// cell it touches is solid: then the table must not answer for it.
    bool open_runs_of(const Aabb& box, std::vector<std::int32_t>& out) const;
    /// The same cells as row words: triples (word, low 32 bits, high 32 bits) appended
    /// to `out` (cleared first), one per 64-bit word of a row that holds any of them,
    /// increasing words; the mask's bit b of word w is open cell 64w + b. Testing a
    /// box against a row's words is then one AND per word (a block's open cells span
    /// at most two words). `runs` is scratch. False when open_runs_of() is.
    bool open_words_of(const Aabb& box, std::vector<std::int32_t>& out,
                       std::vector<std::int32_t>& runs) const;

    /// Pairs (ordered, self pairs included) whose bit is clear, i.e. proven hidden.
    [[nodiscard]] std::uint64_t hidden_pairs() const;
    /// Bytes of the rows and indexes held in memory.
    [[nodiscard]] std::size_t memory_bytes() const;

    /// Same grid, same open and uncovered cells, same answers (both dense or both
    /// compressed).
    friend bool operator==(const CellVisibilityTable& a, const CellVisibilityTable& b);

private:
    /// The valid bits of word `w` of a row.
    [[nodiscard]] std::uint64_t full_word(std::size_t w) const;

    CellGrid grid_;
    glm::ivec3 block_dims_{0};
    std::vector<std::uint32_t> open_;
    std::vector<std::uint32_t> uncovered_;
    std::vector<OpenCell> open_of_;
    /// Per grid cell: the open cells before it in block order.
    std::vector<std::int32_t> open_before_;
    std::size_t words_per_row_ = 0;
    /// Dense rows (before compress()).
    std::vector<std::uint64_t> bits_;
    /// Compressed rows: per row class_words_per_row_ words of 2-bit codes (0: all
    /// hidden, 1: all visible, 2: literal), and the row's literals from
    /// literal_start_[row].
    std::size_t class_words_per_row_ = 0;
    std::vector<std::uint64_t> classes_;
    std::vector<std::uint64_t> literal_start_;
    std::vector<std::uint64_t> literals_;
};

} // namespace dsoc::visibility
