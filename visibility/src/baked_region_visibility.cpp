#include "dsoc/visibility/baked_region_visibility.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace dsoc::visibility {

namespace {
/// What a slab of the built range holds (bits of slab_open_).
constexpr char kSlabSolid = 0;
constexpr char kSlabOpen = 1;
constexpr char kSlabUncovered = 2;
} // namespace

BakedRegionVisibility::BakedRegionVisibility(std::shared_ptr<const CellVisibilityTable> table,
                                             std::unique_ptr<RegionVisibility> next,
                                             NextFor next_for,
                                             std::shared_ptr<const CellBlockUnions> blocks)
    : table_(std::move(table)), blocks_(std::move(blocks)), next_(std::move(next)),
      next_for_(next_ != nullptr ? next_for : NextFor::after_table) {}

void BakedRegionVisibility::build(const Aabb& region) {
    region_ = region;
    next_built_ = false;
    if (next_ && next_for_ == NextFor::after_table) {
        next_->build(region);
    }
    glm::ivec3 lo;
    glm::ivec3 hi;
    if (!table_->grid().range_of(region, lo, hi)) {
        active_ = false;
        partial_ = false;
        built_lo_ = glm::ivec3(1);
        built_hi_ = glm::ivec3(0);
        return;
    }
    if (lo == built_lo_ && hi == built_hi_) {
        return; // the same cells: the same union (and the same active_ and partial_)
    }
    if (blocks_ != nullptr && CellBlockUnions::covers(lo, hi)) {
        build_from_blocks(lo, hi);
    } else {
        build_from_slabs(lo, hi);
    }
    built_lo_ = lo;
    built_hi_ = hi;
}

void BakedRegionVisibility::build_from_blocks(glm::ivec3 lo, glm::ivec3 hi) {
    const CellGrid& grid = table_->grid();
    active_ = false;
    partial_ = false;
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            for (int x = lo.x; x <= hi.x; ++x) {
                const OpenCell c = table_->open_index(grid.index({x, y, z}));
                active_ = active_ || c >= 0;
                // An eye may be where the table says nothing: the union speaks for the
                // eyes in the covered cells only.
                partial_ = partial_ || c == kUncoveredCell;
            }
        }
    }
    visible_.assign(table_->words_per_row(), 0);
    if (active_) {
        blocks_->or_range_into(lo, hi, visible_);
    }
}

void BakedRegionVisibility::build_from_slabs(glm::ivec3 lo, glm::ivec3 hi) {
    // The union is kept as one slab per x of the range (the rows of that x's cells);
    // when only the x range moved, the slabs of the xs kept are reused.
    const bool same_yz = lo.y == slabs_lo_.y && hi.y == slabs_hi_.y && lo.z == slabs_lo_.z &&
                         hi.z == slabs_hi_.z && slabs_lo_.x <= slabs_hi_.x;
    const CellGrid& grid = table_->grid();
    const std::size_t words = table_->words_per_row();
    const auto slabs = static_cast<std::size_t>(hi.x - lo.x + 1);
    // The slabs of the xs both ranges hold move (in place) to their new places.
    int keep_lo = 1;
    int keep_hi = 0;
    if (same_yz) {
        keep_lo = std::max(lo.x, slabs_lo_.x);
        keep_hi = std::min(hi.x, slabs_hi_.x);
    }
    const std::size_t old_slabs = slab_open_.size();
    slabs_.resize(std::max(old_slabs, slabs) * words);
    slab_open_.resize(std::max(old_slabs, slabs), 0);
    if (keep_lo <= keep_hi) {
        const auto from = static_cast<std::size_t>(keep_lo - slabs_lo_.x);
        const auto to = static_cast<std::size_t>(keep_lo - lo.x);
        const auto count = static_cast<std::size_t>(keep_hi - keep_lo + 1);
        std::memmove(slabs_.data() + to * words, slabs_.data() + from * words,
                     count * words * sizeof(std::uint64_t));
        std::memmove(slab_open_.data() + to, slab_open_.data() + from, count);
    }
    slabs_.resize(slabs * words);
    slab_open_.resize(slabs);
    for (int x = lo.x; x <= hi.x; ++x) {
        if (x >= keep_lo && x <= keep_hi) {
            continue;
        }
        const auto k = static_cast<std::size_t>(x - lo.x);
        const std::span<std::uint64_t> slab(slabs_.data() + k * words, words);
        std::fill(slab.begin(), slab.end(), 0);
        slab_open_[k] = kSlabSolid;
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                const OpenCell c = table_->open_index(grid.index({x, y, z}));
                if (c >= 0) {
                    slab_open_[k] |= kSlabOpen;
                    table_->or_row_into(c, slab);
                } else if (c == kUncoveredCell) {
                    slab_open_[k] |= kSlabUncovered;
                }
            }
        }
    }
    slabs_lo_ = lo;
    slabs_hi_ = hi;
    visible_.assign(words, 0);
    active_ = false;
    partial_ = false;
    for (std::size_t k = 0; k < slabs; ++k) {
        // An eye may be where the table says nothing: the union speaks for the eyes
        // in the covered cells only.
        partial_ = partial_ || (slab_open_[k] & kSlabUncovered) != 0;
        if ((slab_open_[k] & kSlabOpen) != 0) {
            active_ = true;
            const std::uint64_t* slab = slabs_.data() + k * words;
            for (std::size_t w = 0; w < words; ++w) {
                visible_[w] |= slab[w];
            }
        }
    }
}

bool BakedRegionVisibility::hidden(const std::int32_t* words, std::size_t count) const {
    std::uint64_t seen = 0;
    for (std::size_t k = 0; k + 2 < count; k += 3) {
        const std::uint64_t mask = static_cast<std::uint32_t>(words[k + 1]) |
                                   std::uint64_t{static_cast<std::uint32_t>(words[k + 2])} << 32;
        seen |= visible_[static_cast<std::size_t>(words[k])] & mask;
    }
    return seen == 0;
}

bool BakedRegionVisibility::prepared_hidden(const PreparedBox& p) const {
    return active_ && !partial_ && p.prepared && hidden(p.keys);
}

bool BakedRegionVisibility::box_hidden(const Aabb& box) const {
    return active_ && !partial_ && table_->open_words_of(box, scratch_, scratch_runs_) &&
           hidden(scratch_);
}

const RegionVisibility& BakedRegionVisibility::fallback() const {
    if (!next_built_) {
        next_->build(region_);
        next_built_ = true;
    }
    return *next_;
}

Visibility BakedRegionVisibility::covered_answer(bool hidden_from_covered, const Aabb& box) const {
    if (!hidden_from_covered) {
        return Visibility::visible; // an eye of a covered cell may see it
    }
    return partial_ ? fallback().test_box(box) : Visibility::occluded;
}

Visibility BakedRegionVisibility::where_uncovered_answer(const Aabb& box) const {
    if (!active_ || !table_->open_words_of(box, scratch_, scratch_runs_)) {
        return fallback().test_box(box);
    }
    return covered_answer(hidden(scratch_), box);
}

Visibility BakedRegionVisibility::test_box(const Aabb& box) const {
    if (next_for_ == NextFor::where_uncovered) {
        return where_uncovered_answer(box);
    }
    if (box_hidden(box)) {
        return Visibility::occluded;
    }
    return next_ ? next_->test_box(box) : Visibility::visible;
}

Visibility BakedRegionVisibility::test_box_quick(const Aabb& box) const {
    if (next_for_ == NextFor::where_uncovered) {
        return where_uncovered_answer(box);
    }
    if (box_hidden(box)) {
        return Visibility::occluded;
    }
    return next_ ? next_->test_box_quick(box) : Visibility::visible;
}

Visibility BakedRegionVisibility::test_box_hinted(const Aabb& box, std::uint32_t& hint) const {
    if (next_for_ == NextFor::where_uncovered) {
        return where_uncovered_answer(box);
    }
    if (box_hidden(box)) {
        return Visibility::occluded;
    }
    return next_ ? next_->test_box_hinted(box, hint) : Visibility::visible;
}

void BakedRegionVisibility::prepare(const Aabb& box, PreparedBox& out) const {
    out.box = box;
    thread_local std::vector<std::int32_t> runs;
    out.prepared = table_->open_words_of(box, out.keys, runs);
    // A next stage that answers only where the table cannot tests the plain box: it is
    // rarely asked, and preparing every box for it would cost every tick.
    if (next_ && next_for_ == NextFor::after_table && next_->has_prepared_stage()) {
        out.inner.resize(1);
        next_->prepare(box, out.inner.front());
    } else {
        out.inner.clear();
    }
}

template <class AskNext>
Visibility BakedRegionVisibility::table_then(const PreparedBox& p, AskNext&& ask_next) const {
    const bool hidden = prepared_hidden(p);
    if (!next_) { // the table alone: no branch on the answer
        return hidden ? Visibility::occluded : Visibility::visible;
    }
    if (next_for_ == NextFor::where_uncovered) {
        return test_prepared_coarse(p); // every prepared test is the coarse one
    }
    if (hidden) {
        return Visibility::occluded;
    }
    return ask_next(*next_);
}

// The next stage gets its own preparation of the box when it has one (same box).
Visibility BakedRegionVisibility::test_prepared(const PreparedBox& p) const {
    return table_then(p, [&p](const RegionVisibility& next) {
        return p.inner.empty() ? next.test_box(p.box) : next.test_prepared(p.inner.front());
    });
}

Visibility BakedRegionVisibility::test_prepared_quick(const PreparedBox& p) const {
    return table_then(p, [&p](const RegionVisibility& next) {
        return p.inner.empty() ? next.test_box_quick(p.box)
                               : next.test_prepared_quick(p.inner.front());
    });
}

Visibility BakedRegionVisibility::test_prepared_hinted(const PreparedBox& p,
                                                       std::uint32_t& hint) const {
    return table_then(p, [&p, &hint](const RegionVisibility& next) {
        return p.inner.empty() ? next.test_box_hinted(p.box, hint)
                               : next.test_prepared_hinted(p.inner.front(), hint);
    });
}

Visibility BakedRegionVisibility::test_prepared_coarse(const PreparedBox& p) const {
    if (next_for_ == NextFor::where_uncovered) {
        return active_ && p.prepared ? covered_answer(hidden(p.keys), p.box)
                                     : fallback().test_box(p.box);
    }
    return prepared_hidden(p) ? Visibility::occluded : Visibility::visible;
}

void BakedRegionVisibility::coarse_hidden_all(const PackedPreparedBoxes& boxes,
                                              std::span<std::uint8_t> answers) const {
    // test_prepared_coarse() for every box, with the table's bit tests inline on the
    // packed keys: only a box the table cannot answer (behind the table alone, where it
    // does not cover) takes the call.
    const bool answer_rest = next_for_ == NextFor::where_uncovered;
    const std::int32_t* keys = boxes.keys.data();
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        const PreparedBox* p = boxes.boxes[i];
        if (p == nullptr) {
            answers[i] = 0;
        } else if (active_ && boxes.prepared[i] != 0) {
            const std::uint32_t start = boxes.key_start[i];
            const bool hidden_from_covered = hidden(keys + start, boxes.key_start[i + 1] - start);
            answers[i] = !partial_ ? hidden_from_covered
                                   : answer_rest && hidden_from_covered &&
                                         fallback().test_box(p->box) == Visibility::occluded;
        } else {
            answers[i] = answer_rest && fallback().test_box(p->box) == Visibility::occluded ? 1 : 0;
        }
    }
}

void BakedRegionVisibility::merge_prepared(PreparedBox& into, const PreparedBox& more) const {
    // Both lists have increasing words (open_words_of() makes them so, and so does
    // this): one pass, a word in both gets the OR of its masks.
    thread_local std::vector<std::int32_t> merged;
    merged.clear();
    const auto& a = into.keys;
    const auto& b = more.keys;
    std::size_t i = 0;
    std::size_t j = 0;
    while (i + 2 < a.size() || j + 2 < b.size()) {
        const bool take_a = j + 2 >= b.size() || (i + 2 < a.size() && a[i] <= b[j]);
        const std::vector<std::int32_t>& from = take_a ? a : b;
        std::size_t& k = take_a ? i : j;
        if (!merged.empty() && merged[merged.size() - 3] == from[k]) {
            merged[merged.size() - 2] |= from[k + 1];
            merged.back() |= from[k + 2];
        } else {
            merged.insert(merged.end(), from.begin() + static_cast<std::ptrdiff_t>(k),
                          from.begin() + static_cast<std::ptrdiff_t>(k + 3));
        }
        k += 3;
    }
    into.keys.assign(merged.begin(), merged.end());
    into.inner.clear(); // the next stage's preparation was of one member's box only
}

RegionVisibilityFactory with_baked_stage(std::shared_ptr<const CellVisibilityTable> table,
                                         RegionVisibilityFactory make_next,
                                         BakedRegionVisibility::NextFor next_for) {
    if (table == nullptr) {
        return make_next;
    }
    auto blocks = std::make_shared<const CellBlockUnions>(*table);
    return [table = std::move(table), blocks = std::move(blocks), make_next = std::move(make_next),
            next_for] {
        return std::make_unique<BakedRegionVisibility>(table, make_next ? make_next() : nullptr,
                                                       next_for, blocks);
    };
}

} // namespace dsoc::visibility
