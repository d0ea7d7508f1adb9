#include "dsoc/visibility/cell_visibility.hpp"

#include "row_codes.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cassert>

#include <glm/common.hpp>

namespace dsoc::visibility {

namespace {

constexpr int kB = kTableBlockCells;
constexpr std::uint64_t kCellsPerBlock = kB * kB * kB;

using row_codes::kHidden;
using row_codes::kLiteral;
using row_codes::kVisible;

} // namespace

CellVisibilityTable::CellVisibilityTable(const CellGrid& grid, std::vector<std::uint32_t> open,
                                         std::vector<std::uint32_t> uncovered, Rows rows)
    : grid_(grid), block_dims_((grid.dims + (kB - 1)) / kB), open_(std::move(open)),
      uncovered_(std::move(uncovered)), open_of_(grid.cell_count(), kSolidCell),
      words_per_row_((open_.size() + 63) / 64),
      bits_(rows == Rows::dense ? open_.size() * words_per_row_ : 0, 0) {
    std::ranges::sort(open_, {}, [this](std::uint32_t c) { return block_rank(c); });
    std::ranges::sort(uncovered_);
    for (const std::uint32_t c : uncovered_) {
        open_of_[c] = kUncoveredCell;
    }
    for (std::size_t i = 0; i < open_.size(); ++i) {
        open_of_[open_[i]] = static_cast<OpenCell>(i);
    }
    // Every grid cell in block order, counting the open cells met before it.
    open_before_.assign(grid.cell_count(), 0);
    std::int32_t count = 0;
    for (int bz = 0; bz < block_dims_.z; ++bz) {
        for (int by = 0; by < block_dims_.y; ++by) {
            for (int bx = 0; bx < block_dims_.x; ++bx) {
                const glm::ivec3 lo{bx * kB, by * kB, bz * kB};
                const glm::ivec3 hi = glm::min(lo + kB, grid.dims);
                for (int z = lo.z; z < hi.z; ++z) {
                    for (int y = lo.y; y < hi.y; ++y) {
                        for (int x = lo.x; x < hi.x; ++x) {
                            const std::uint32_t cell = grid.index({x, y, z});
                            open_before_[cell] = count;
                            count += open_of_[cell] >= 0 ? 1 : 0;
                        }
                    }
                }
            }
        }
    }
}

std::uint64_t CellVisibilityTable::block_rank(std::uint32_t cell) const {
    const glm::ivec3 c = grid_.coords(cell);
    const glm::ivec3 b = c / kB;
    const glm::ivec3 in = c - b * kB;
    const auto block =
        static_cast<std::uint64_t>((b.z * block_dims_.y + b.y) * block_dims_.x + b.x);
    return block * kCellsPerBlock + static_cast<std::uint64_t>((in.z * kB + in.y) * kB + in.x);
}

std::uint64_t CellVisibilityTable::full_word(std::size_t w) const {
    return row_codes::full_word(open_.size(), w);
}

bool CellVisibilityTable::may_see(OpenCell from, OpenCell to) const {
    const auto w = static_cast<std::size_t>(to) >> 6;
    const std::uint64_t bit = std::uint64_t{1} << (to & 63);
    const auto row = static_cast<std::size_t>(from);
    if (!compressed()) {
        return (bits_[row * words_per_row_ + w] & bit) != 0;
    }
    const std::uint64_t* cls = classes_.data() + row * class_words_per_row_;
    const std::uint64_t code = cls[w >> 5] >> (2 * (w & 31)) & 3u;
    if (code != kLiteral) {
        return code == kVisible;
    }
    // The literal's place: the literals of the row's earlier words.
    std::uint64_t before = 0;
    for (std::size_t k = 0; k < (w >> 5); ++k) {
        before += static_cast<std::uint64_t>(std::popcount(cls[k] & 0xaaaaaaaaaaaaaaaaull));
    }
    const std::uint64_t below = (std::uint64_t{1} << (2 * (w & 31))) - 1;
    before +=
        static_cast<std::uint64_t>(std::popcount(cls[w >> 5] & below & 0xaaaaaaaaaaaaaaaaull));
    return (literals_[literal_start_[row] + before] & bit) != 0;
}

void CellVisibilityTable::or_row_into(OpenCell from, std::span<std::uint64_t> out) const {
    assert(out.size() == words_per_row_);
    const auto row = static_cast<std::size_t>(from);
    if (!compressed()) {
        const std::uint64_t* bits = bits_.data() + row * words_per_row_;
        for (std::size_t k = 0; k < words_per_row_; ++k) {
            out[k] |= bits[k];
        }
        return;
    }
    row_codes::or_coded_row(classes_.data() + row * class_words_per_row_, class_words_per_row_,
                            literals_.data() + literal_start_[row], out.data());
    if (words_per_row_ > 0) {
        out[words_per_row_ - 1] &= full_word(words_per_row_ - 1);
    }
}

void CellVisibilityTable::set_visible_atomic(OpenCell a, OpenCell b) {
    assert(!compressed());
    const auto set = [this](OpenCell from, OpenCell to) {
        std::atomic_ref<std::uint64_t> word(bits_[static_cast<std::size_t>(from) * words_per_row_ +
                                                  (static_cast<std::size_t>(to) >> 6)]);
        const std::uint64_t bit = std::uint64_t{1} << (to & 63);
        if ((word.load(std::memory_order_relaxed) & bit) == 0) {
            word.fetch_or(bit, std::memory_order_relaxed);
        }
    };
    set(a, b);
    set(b, a);
}

void CellVisibilityTable::compress() {
    if (compressed()) {
        return;
    }
    class_words_per_row_ = class_words_per_row();
    classes_.assign(open_.size() * class_words_per_row_, 0);
    literal_start_.assign(1, 0);
    literals_.clear();
    for (std::size_t r = 0; r < open_.size(); ++r) {
        row_codes::encode_row(bits_.data() + r * words_per_row_, open_.size(),
                              classes_.data() + r * class_words_per_row_, literals_);
        literal_start_.push_back(literals_.size());
    }
    literals_.shrink_to_fit();
    bits_.clear();
    bits_.shrink_to_fit();
}

std::optional<std::string>
CellVisibilityTable::adopt_compressed(std::vector<std::uint64_t> classes,
                                      std::vector<std::uint64_t> literals) {
    const std::size_t per_row = class_words_per_row();
    if (classes.size() != open_.size() * per_row) {
        return std::to_string(classes.size()) + " class words for " + std::to_string(open_.size()) +
               " rows of " + std::to_string(per_row);
    }
    std::vector<std::uint64_t> starts{0};
    starts.reserve(open_.size() + 1);
    std::uint64_t literal = 0;
    for (std::size_t r = 0; r < open_.size(); ++r) {
        const std::uint64_t* cls = classes.data() + r * per_row;
        for (std::size_t w = 0; w < per_row * 32; ++w) {
            const std::uint64_t code = cls[w >> 5] >> (2 * (w & 31)) & 3u;
            if (code != kHidden && w >= words_per_row_) {
                return "row " + std::to_string(r) + " has a code past its last word";
            }
            if (code == kLiteral) {
                if (literal >= literals.size()) {
                    return "more literal codes than the " + std::to_string(literals.size()) +
                           " literal words";
                }
                const std::uint64_t v = literals[literal++];
                if (v == 0 || v == full_word(w) || (v & ~full_word(w)) != 0) {
                    return "row " + std::to_string(r) + " word " + std::to_string(w) +
                           ": a literal that is all hidden, all visible or past the last cell";
                }
            } else if (code != kHidden && code != kVisible) {
                return "row " + std::to_string(r) + " word " + std::to_string(w) +
                       ": unknown code " + std::to_string(code);
            }
        }
        starts.push_back(literal);
    }
    if (literal != literals.size()) {
        return std::to_string(literals.size() - literal) + " literal words no code refers to";
    }
    // Swap the rows in, check the diagonal, swap them back out on failure.
    class_words_per_row_ = per_row;
    classes_.swap(classes);
    literal_start_.swap(starts);
    literals_.swap(literals);
    for (std::size_t r = 0; r < open_.size(); ++r) {
        if (!may_see(static_cast<OpenCell>(r), static_cast<OpenCell>(r))) {
            classes_.swap(classes);
            literal_start_.swap(starts);
            literals_.swap(literals);
            return "open cell " + std::to_string(r) + " does not see itself";
        }
    }
    bits_.clear();
    bits_.shrink_to_fit();
    return std::nullopt;
}

bool CellVisibilityTable::open_runs_of(const Aabb& box, std::vector<std::int32_t>& out) const {
    out.clear();
    glm::ivec3 lo;
    glm::ivec3 hi;
    if (!grid_.range_of(box, lo, hi)) {
        return false;
    }
    const bool any_uncovered = !uncovered_.empty();
    // One run per row of cells within each block the box crosses.
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            if (any_uncovered) {
                const OpenCell* row = open_of_.data() + grid_.index({lo.x, y, z});
                for (int x = 0; x <= hi.x - lo.x; ++x) {
                    if (row[x] == kUncoveredCell) {
                        out.clear();
                        return false;
                    }
                }
            }
            for (int x0 = lo.x; x0 <= hi.x;) {
                const int x1 = std::min(hi.x, (x0 / kB + 1) * kB - 1);
                const std::uint32_t last = grid_.index({x1, y, z});
                const std::int32_t first = open_before_[grid_.index({x0, y, z})];
                const std::int32_t end = open_before_[last] + (open_of_[last] >= 0 ? 1 : 0);
                if (first != end) {
                    out.push_back(first);
                    out.push_back(end);
                }
                x0 = x1 + 1;
            }
        }
    }
    if (out.empty()) {
        return false;
    }
    // Sort the runs by their first cell (insertion sort on the pairs in place: few
    // runs, and those of one block come in order) and join touching ones.
    for (std::size_t k = 2; k < out.size(); k += 2) {
        const std::int32_t first = out[k];
        const std::int32_t end = out[k + 1];
        std::size_t j = k;
        for (; j > 0 && out[j - 2] > first; j -= 2) {
            out[j] = out[j - 2];
            out[j + 1] = out[j - 1];
        }
        out[j] = first;
        out[j + 1] = end;
    }
    std::size_t kept = 2;
    for (std::size_t k = 2; k < out.size(); k += 2) {
        if (out[kept - 1] >= out[k]) {
            out[kept - 1] = std::max(out[kept - 1], out[k + 1]);
        } else {
            out[kept] = out[k];
            out[kept + 1] = out[k + 1];
            kept += 2;
        }
    }
    out.resize(kept);
    return true;
}

bool CellVisibilityTable::open_words_of(const Aabb& box, std::vector<std::int32_t>& out,
                                        std::vector<std::int32_t>& runs) const {
    out.clear();
    if (!open_runs_of(box, runs)) {
        return false;
    }
    // The runs are sorted and disjoint, so their words come in order; a word two runs
    // share is the last triple.
    const auto add = [&out](std::size_t word, std::uint64_t mask) {
        if (!out.empty() && static_cast<std::size_t>(out[out.size() - 3]) == word) {
            mask |= static_cast<std::uint32_t>(out[out.size() - 2]) |
                    std::uint64_t{static_cast<std::uint32_t>(out.back())} << 32;
            out.resize(out.size() - 3);
        }
        out.push_back(static_cast<std::int32_t>(word));
        out.push_back(static_cast<std::int32_t>(static_cast<std::uint32_t>(mask)));
        out.push_back(static_cast<std::int32_t>(static_cast<std::uint32_t>(mask >> 32)));
    };
    for (std::size_t k = 0; k + 1 < runs.size(); k += 2) {
        const auto first = static_cast<std::size_t>(runs[k]);
        const auto last = static_cast<std::size_t>(runs[k + 1]) - 1;
        for (std::size_t w = first >> 6; w <= last >> 6; ++w) {
            const std::size_t lo = std::max(first, w << 6) & 63;
            const std::size_t hi = std::min(last, (w << 6) + 63) & 63;
            add(w, (~std::uint64_t{0} << lo) & (~std::uint64_t{0} >> (63 - hi)));
        }
    }
    return true;
}

std::uint64_t CellVisibilityTable::hidden_pairs() const {
    std::uint64_t visible = 0;
    if (!compressed()) {
        for (const std::uint64_t w : bits_) {
            visible += static_cast<std::uint64_t>(std::popcount(w));
        }
    } else {
        for (const std::uint64_t w : literals_) {
            visible += static_cast<std::uint64_t>(std::popcount(w));
        }
        for (std::size_t r = 0; r < open_.size(); ++r) {
            const std::uint64_t* cls = classes_.data() + r * class_words_per_row_;
            for (std::size_t w = 0; w < words_per_row_; ++w) {
                if ((cls[w >> 5] >> (2 * (w & 31)) & 3u) == kVisible) {
                    visible += static_cast<std::uint64_t>(std::popcount(full_word(w)));
                }
            }
        }
    }
    const auto n = static_cast<std::uint64_t>(open_.size());
    return n * n - visible;
}

std::size_t CellVisibilityTable::memory_bytes() const {
    return (bits_.size() + classes_.size() + literal_start_.size() + literals_.size()) *
               sizeof(std::uint64_t) +
           (open_.size() + uncovered_.size()) * sizeof(std::uint32_t) +
           open_of_.size() * sizeof(OpenCell) + open_before_.size() * sizeof(std::int32_t);
}

bool operator==(const CellVisibilityTable& a, const CellVisibilityTable& b) {
    return a.grid_.dims == b.grid_.dims && a.grid_.origin == b.grid_.origin &&
           a.grid_.cell_size == b.grid_.cell_size && a.open_ == b.open_ &&
           a.uncovered_ == b.uncovered_ && a.bits_ == b.bits_ && a.classes_ == b.classes_ &&
           a.literal_start_ == b.literal_start_ && a.literals_ == b.literals_;
}

} // namespace dsoc::visibility
