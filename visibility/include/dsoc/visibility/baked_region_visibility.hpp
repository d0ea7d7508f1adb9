#pragma once
// A baked cell visibility table (cell_visibility.hpp) as the first stage of a region
// culler: the union of the rows of the open cells a client's eye region touches is
// conservative for every eye of the region, so a box none of whose open cells is in
// that union is hidden from all of them. A prepared box costs a few bit tests.
//
// A region or box the table does not cover (part of it outside the grid or in an
// uncovered cell, or only solid cells) is never answered by guess: it goes to the next
// stage, or is `visible` when there is none. A region part in covered cells and part in
// uncovered ones ("partial") still has a union for the eyes of its covered cells: a box
// some of them may see is visible, and only a box hidden from all of them goes on.
//
// Two ways to chain the next stage: `after_table`, it answers every box the table does
// not prove hidden (the table, then the exact stages); `where_uncovered`, it answers
// only what the table does not cover and the table's "visible" stands (the table
// alone, with the exact stages where it has nothing to say). In the second way the next
// stage is built only when first needed after build(), so test_*() of one culler must
// come from one thread at a time (as the InterestManager's per-client pass does).

#include "dsoc/visibility/cell_block_unions.hpp"
#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/region_visibility.hpp"

#include <memory>
#include <vector>

namespace dsoc::visibility {

class BakedRegionVisibility final : public RegionVisibility {
public:
    enum class NextFor { after_table, where_uncovered };

    /// `next` (may be null: the table alone, "visible" for what it does not cover)
    /// answers what the table passes or does not cover (`after_table`), or only what
    /// it does not cover (`where_uncovered`). `blocks` (may be null) are `table`'s
    /// block unions, for building a region's union from fewer rows (the same union).
    BakedRegionVisibility(std::shared_ptr<const CellVisibilityTable> table,
                          std::unique_ptr<RegionVisibility> next,
                          NextFor next_for = NextFor::after_table,
                          std::shared_ptr<const CellBlockUnions> blocks = nullptr);

    void build(const Aabb& region) override;
    [[nodiscard]] Visibility test_box(const Aabb& box) const override;
    [[nodiscard]] Visibility test_box_quick(const Aabb& box) const override;
    [[nodiscard]] Visibility test_box_hinted(const Aabb& box, std::uint32_t& hint) const override;

    /// Prepared boxes carry their open cells, so the table costs a few bit tests.
    [[nodiscard]] bool has_prepared_stage() const override { return true; }
    void prepare(const Aabb& box, PreparedBox& out) const override;
    [[nodiscard]] Visibility test_prepared(const PreparedBox& p) const override;
    [[nodiscard]] Visibility test_prepared_quick(const PreparedBox& p) const override;
    [[nodiscard]] Visibility test_prepared_hinted(const PreparedBox& p,
                                                  std::uint32_t& hint) const override;
    /// A pair's first answer is a few bit tests: TBVs and entity clusters do not pay.
    [[nodiscard]] bool pair_shortcuts_pay() const override { return false; }
    /// The table's answer where it covers the box and the region (the next stage is
    /// skipped when it passes the box); elsewhere `visible`, or with `where_uncovered`
    /// the next stage's test_box(). With `where_uncovered` every test of a box the
    /// table does not cover is that one (no quick test, no hint), so that every
    /// prepared test is the coarse one.
    [[nodiscard]] Visibility test_prepared_coarse(const PreparedBox& p) const override;
    /// No next stage, or one `where_uncovered`: every prepared test is the coarse one.
    [[nodiscard]] bool prepared_tests_are_coarse() const override {
        return next_ == nullptr || next_for_ == NextFor::where_uncovered;
    }
    void coarse_hidden_all(const PackedPreparedBoxes& boxes,
                           std::span<std::uint8_t> hidden) const override;
    /// Keys are row words of open cells (CellVisibilityTable::open_words_of): the union
    /// of both lists, one triple per word, masks ORed.
    void merge_prepared(PreparedBox& into, const PreparedBox& more) const override;

    /// True when the last build() found the region covered by the table.
    [[nodiscard]] bool active() const { return active_ && !partial_; }
    /// True when the last build() found open cells of the region covered and others
    /// not: the table answers `visible` for what an eye of the covered ones may see
    /// (behind the table alone), and nothing else.
    [[nodiscard]] bool partial() const { return active_ && partial_; }
    /// With `where_uncovered`: whether the next stage was built for the last region
    /// (it is only when something the table does not cover was tested).
    [[nodiscard]] bool next_built() const { return next_built_; }

private:
    /// True when the table proves every open cell of `words` (open_words_of()'s
    /// triples) hidden from the built region.
    [[nodiscard]] bool hidden(const std::vector<std::int32_t>& words) const {
        return hidden(words.data(), words.size());
    }
    /// The same for `count` ints of triples at `words`.
    [[nodiscard]] bool hidden(const std::int32_t* words, std::size_t count) const;
    [[nodiscard]] bool box_hidden(const Aabb& box) const;
    /// The table proves a box prepared by this stage hidden from the built region.
    [[nodiscard]] bool prepared_hidden(const PreparedBox& p) const;
    /// A prepared test, in the stages' order: the table's answer where it settles `p`,
    /// else `ask_next(next stage)` (the next stage's test of the same kind).
    template <class AskNext>
    [[nodiscard]] Visibility table_then(const PreparedBox& p, AskNext&& ask_next) const;
    /// With `where_uncovered`: the next stage, built for the last region first.
    [[nodiscard]] const RegionVisibility& fallback() const;
    /// With `where_uncovered`, every test of `box`: the table's answer where it covers
    /// the box and the region, else the next stage's test_box().
    [[nodiscard]] Visibility where_uncovered_answer(const Aabb& box) const;
    /// With `where_uncovered`, a box the table covers, from whether no eye of the
    /// region's covered cells may see it: `visible` if one may, else the next stage's
    /// answer where the region is partial, else `occluded`.
    [[nodiscard]] Visibility covered_answer(bool hidden_from_covered, const Aabb& box) const;

    /// Builds visible_ for the cell range [lo, hi] from the table's rows, one slab of
    /// them per x (the slabs of the xs the last such build had are reused when only the
    /// x range moved), and sets active_ and partial_.
    void build_from_slabs(glm::ivec3 lo, glm::ivec3 hi);
    /// The same from blocks_ (CellBlockUnions::covers() the range).
    void build_from_blocks(glm::ivec3 lo, glm::ivec3 hi);

    std::shared_ptr<const CellVisibilityTable> table_;
    std::shared_ptr<const CellBlockUnions> blocks_;
    std::unique_ptr<RegionVisibility> next_;
    NextFor next_for_ = NextFor::after_table;
    bool active_ = false;             ///< the region has covered open cells: visible_ is theirs
    bool partial_ = false;            ///< ... and uncovered ones too
    Aabb region_;                     ///< the last built region
    mutable bool next_built_ = false; ///< `where_uncovered`: next_ built for region_
    glm::ivec3 built_lo_{1};
    glm::ivec3 built_hi_{0};
    std::vector<std::uint64_t> visible_; ///< union of the region's rows
    /// Per x of the range [slabs_lo_, slabs_hi_] (empty when slabs_lo_.x > slabs_hi_.x),
    /// the union of the rows of that x's cells, and whether it has an open cell (bit 0)
    /// and an uncovered one (bit 1).
    glm::ivec3 slabs_lo_{1};
    glm::ivec3 slabs_hi_{0};
    std::vector<std::uint64_t> slabs_;
    std::vector<char> slab_open_;
    mutable std::vector<std::int32_t> scratch_;
    mutable std::vector<std::int32_t> scratch_runs_;
};

/// Puts the table in front of every culler `make_next` makes (`make_next` empty: the
/// table alone), the next stage answering as `next_for` says; returns `make_next`
/// itself when `table` is null. The table's block unions are made here, once, and
/// shared by every culler.
[[nodiscard]] RegionVisibilityFactory with_baked_stage(
    std::shared_ptr<const CellVisibilityTable> table, RegionVisibilityFactory make_next,
    BakedRegionVisibility::NextFor next_for = BakedRegionVisibility::NextFor::after_table);

} // namespace dsoc::visibility
