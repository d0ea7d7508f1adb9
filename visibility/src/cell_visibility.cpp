#include "dsoc/visibility/cell_visibility.hpp"

#include <atomic>
#include <bit>

namespace dsoc::visibility {

CellVisibilityTable::CellVisibilityTable(const CellGrid& grid, std::vector<std::uint32_t> open)
    : grid_(grid), open_(std::move(open)), open_of_(grid.cell_count(), kSolidCell),
      open_before_(grid.cell_count() + 1, 0), words_per_row_((open_.size() + 63) / 64),
      bits_(open_.size() * words_per_row_, 0) {
    for (std::size_t i = 0; i < open_.size(); ++i) {
        open_of_[open_[i]] = static_cast<OpenCell>(i);
    }
    std::int32_t count = 0;
    for (std::size_t g = 0; g < open_of_.size(); ++g) {
        open_before_[g] = count;
        count += open_of_[g] != kSolidCell ? 1 : 0;
    }
    open_before_.back() = count;
}

void CellVisibilityTable::set_visible_atomic(OpenCell a, OpenCell b) {
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

bool CellVisibilityTable::open_runs_of(const Aabb& box, std::vector<std::int32_t>& out) const {
    out.clear();
    glm::ivec3 lo;
    glm::ivec3 hi;
    if (!grid_.range_of(box, lo, hi)) {
        return false;
    }
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            const std::int32_t first = open_before_[grid_.index({lo.x, y, z})];
            const std::int32_t end = open_before_[grid_.index({hi.x, y, z}) + 1];
            if (first == end) {
                continue;
            }
            if (!out.empty() && out.back() == first) {
                out.back() = end; // continues the previous run
            } else {
                out.push_back(first);
                out.push_back(end);
            }
        }
    }
    return !out.empty();
}

std::uint64_t CellVisibilityTable::hidden_pairs() const {
    std::uint64_t visible = 0;
    for (const std::uint64_t w : bits_) {
        visible += static_cast<std::uint64_t>(std::popcount(w));
    }
    const auto n = static_cast<std::uint64_t>(open_.size());
    return n * n - visible;
}

std::size_t CellVisibilityTable::memory_bytes() const {
    return bits_.size() * sizeof(std::uint64_t) + open_.size() * sizeof(std::uint32_t) +
           open_of_.size() * sizeof(OpenCell) + open_before_.size() * sizeof(std::int32_t);
}

} // namespace dsoc::visibility
