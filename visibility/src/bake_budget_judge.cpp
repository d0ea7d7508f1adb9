#include "bake_budget_judge.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <thread>

namespace dsoc::visibility {

namespace {

/// The sample holds at least this many pairs per worker (or all): the CPU time counted
/// includes the pairs still in the workers' hands.
constexpr std::uint64_t kMinSamplePairsPerThread = 8;

} // namespace

BakeBudgetJudge::BakeBudgetJudge(const BakeBudget& budget, std::uint64_t first, std::uint64_t count,
                                 unsigned threads)
    : budget_(budget), first_(first), left_(count - first),
      sample_end_(
          budget.limited() && count > first
              ? first + std::min<std::uint64_t>(
                            left_, std::max<std::uint64_t>(
                                       kMinSamplePairsPerThread * threads,
                                       static_cast<std::uint64_t>(std::ceil(
                                           budget.sample_fraction * static_cast<double>(left_)))))
              : 0),
      // CPU time over the workers, no more than the cores: a quiet machine's wall time.
      cores_(static_cast<double>(std::thread::hardware_concurrency() > 0
                                     ? std::min(threads, std::thread::hardware_concurrency())
                                     : threads)),
      decided_(sample_end_ == 0) {
    if (sample_end_ != 0) {
        cpu_start_ = cpu_now();
    }
}

double BakeBudgetJudge::cpu_now() const {
    return budget_.cpu_seconds ? budget_.cpu_seconds()
                               : static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

bool BakeBudgetJudge::over_budget_after(std::uint64_t finished) {
    if (decided_.load(std::memory_order_relaxed)) {
        return false;
    }
    const double spent = (cpu_now() - cpu_start_) / cores_;
    if (finished < sample_end_ && !(spent > budget_.sample_fraction * budget_.max_seconds)) {
        return false;
    }
    if (decided_.exchange(true)) {
        return false; // another worker decided
    }
    sample_seconds_ = spent;
    predicted_seconds_ =
        spent * static_cast<double>(left_) / static_cast<double>(finished - first_);
    over_ = predicted_seconds_ > budget_.max_seconds;
    return over_;
}

} // namespace dsoc::visibility
