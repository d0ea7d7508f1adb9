#include "dsoc/visibility/cell_block_unions.hpp"

#include "row_codes.hpp"

#include <algorithm>
#include <array>
#include <cassert>

namespace dsoc::visibility {

namespace {

/// A range's anchors on one axis: at most half its cells, rounded up.
using Anchors = std::array<int, CellBlockUnions::kMaxRangeCells / 2>;

/// The anchors of the blocks that cover [lo, hi] (hi > lo) on one axis: lo, lo + 2, ...,
/// and hi - 1 when the range has an odd number of cells (that block overlaps the one
/// before it). Returns how many were written to `out`.
int anchors_on_axis(int lo, int hi, Anchors& out) {
    int n = 0;
    int a = lo;
    for (; a + 1 <= hi; a += 2) {
        out[static_cast<std::size_t>(n++)] = a;
    }
    if (a <= hi) { // one cell left: the block ending at hi
        out[static_cast<std::size_t>(n++)] = hi - 1;
    }
    return n;
}

} // namespace

CellBlockUnions::CellBlockUnions(const CellVisibilityTable& table)
    : anchors_(glm::max(table.grid().dims - 1, glm::ivec3(0))), bits_(table.open_count()),
      words_(table.words_per_row()), class_words_(row_codes::class_words_for(words_)) {
    const CellGrid& grid = table.grid();
    union_of_.assign(static_cast<std::size_t>(anchors_.x) * static_cast<std::size_t>(anchors_.y) *
                         static_cast<std::size_t>(anchors_.z),
                     -1);
    literal_start_.assign(1, 0);
    std::vector<std::uint64_t> dense(words_);
    std::size_t anchor = 0;
    for (int z = 0; z < anchors_.z; ++z) {
        for (int y = 0; y < anchors_.y; ++y) {
            for (int x = 0; x < anchors_.x; ++x, ++anchor) {
                std::array<OpenCell, 8> cells{};
                std::size_t n = 0;
                for (int k = 0; k < 8; ++k) {
                    const OpenCell c = table.open_index(
                        grid.index({x + (k & 1), y + (k >> 1 & 1), z + (k >> 2 & 1)}));
                    if (c >= 0) {
                        cells[n++] = c;
                    }
                }
                if (n == 0) {
                    continue;
                }
                std::fill(dense.begin(), dense.end(), 0);
                for (std::size_t k = 0; k < n; ++k) {
                    table.or_row_into(cells[k], dense);
                }
                union_of_[anchor] = static_cast<std::int32_t>(literal_start_.size() - 1);
                classes_.resize(classes_.size() + class_words_, 0);
                row_codes::encode_row(dense.data(), bits_,
                                      classes_.data() + classes_.size() - class_words_, literals_);
                literal_start_.push_back(literals_.size());
            }
        }
    }
    classes_.shrink_to_fit();
    literals_.shrink_to_fit();
}

void CellBlockUnions::or_range_into(glm::ivec3 lo, glm::ivec3 hi,
                                    std::span<std::uint64_t> out) const {
    assert(covers(lo, hi) && out.size() == words_);
    std::array<Anchors, 3> at{};
    const int nx = anchors_on_axis(lo.x, hi.x, at[0]);
    const int ny = anchors_on_axis(lo.y, hi.y, at[1]);
    const int nz = anchors_on_axis(lo.z, hi.z, at[2]);
    for (int k = 0; k < nz; ++k) {
        for (int j = 0; j < ny; ++j) {
            const std::size_t line =
                (static_cast<std::size_t>(at[2][static_cast<std::size_t>(k)]) *
                     static_cast<std::size_t>(anchors_.y) +
                 static_cast<std::size_t>(at[1][static_cast<std::size_t>(j)])) *
                static_cast<std::size_t>(anchors_.x);
            for (int i = 0; i < nx; ++i) {
                const std::int32_t u =
                    union_of_[line + static_cast<std::size_t>(at[0][static_cast<std::size_t>(i)])];
                if (u < 0) {
                    continue;
                }
                const auto row = static_cast<std::size_t>(u);
                row_codes::or_coded_row(classes_.data() + row * class_words_, class_words_,
                                        literals_.data() + literal_start_[row], out.data());
            }
        }
    }
    if (words_ > 0) {
        out[words_ - 1] &= row_codes::full_word(bits_, words_ - 1);
    }
}

std::size_t CellBlockUnions::memory_bytes() const {
    return (classes_.size() + literal_start_.size() + literals_.size()) * sizeof(std::uint64_t) +
           union_of_.size() * sizeof(std::int32_t);
}

} // namespace dsoc::visibility
