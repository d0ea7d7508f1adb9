#pragma once
// Judges a running bake against its BakeBudget (cell_bake.hpp): the time of the pairs
// left is predicted from the first of them, at their pace, and a bake over the budget
// is told to give up. Before the sample ends it gives up as soon as the sample has
// cost more than its share of the budget (the prediction can then only be over), so a
// bake far too large costs at most sample_fraction of the budget.

#include "dsoc/visibility/cell_bake.hpp"

#include <atomic>
#include <cstdint>

namespace dsoc::visibility {

class BakeBudgetJudge {
public:
    /// A bake of `count` top pairs, the first `first` resolved before it started, on
    /// `threads` workers. Reads the clock once now when the budget is limited.
    BakeBudgetJudge(const BakeBudget& budget, std::uint64_t first, std::uint64_t count,
                    unsigned threads);

    /// Called by any worker after it resolved a pair, `finished` being the pairs done so
    /// far (this run's and before). Decides once, on the sample's end or sooner; true
    /// when the bake is over its budget. Thread-safe.
    [[nodiscard]] bool over_budget_after(std::uint64_t finished);

    // What was decided; read once the workers are joined.
    [[nodiscard]] bool over_budget() const { return over_; }
    /// The predicted time of the pairs left (0: not decided). [Units: s]
    [[nodiscard]] double predicted_seconds() const { return predicted_seconds_; }
    /// What the sample took. [Units: s]
    [[nodiscard]] double sample_seconds() const { return sample_seconds_; }

private:
    [[nodiscard]] double cpu_now() const;

    const BakeBudget& budget_;
    std::uint64_t first_;
    std::uint64_t left_;
    std::uint64_t sample_end_; ///< 0: no budget
    double cores_;
    double cpu_start_ = 0.0;
    std::atomic<bool> decided_;
    bool over_ = false;
    double predicted_seconds_ = 0.0;
    double sample_seconds_ = 0.0;
};

} // namespace dsoc::visibility
