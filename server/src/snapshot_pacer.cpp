#include "dsoc/server/snapshot_pacer.hpp"

#include "dsoc/protocol/delta_frame.hpp"

#include <algorithm>
#include <cassert>

namespace dsoc::server {

SnapshotPacer::SnapshotPacer(int tick_rate) : unacked_window_(unacked_window_at(tick_rate)) {}

std::uint64_t SnapshotPacer::unacked_window_at(int tick_rate) {
    return std::clamp<std::uint64_t>((static_cast<std::uint64_t>(tick_rate) + 1) / 2, 8,
                                     protocol::kAckedHistory - 1 - kBehindInterval);
}

bool SnapshotPacer::offer(std::uint64_t tick, std::optional<std::uint64_t> acked) {
    assert(tick > last_sent_);
    if (first_tick_ == 0) {
        first_tick_ = tick;
        bucket_start_ = tick;
    }
    const std::uint64_t since = acked.value_or(first_tick_);
    const std::uint64_t age = tick > since ? tick - since : 0;
    if (tick - bucket_start_ >= kBaseWindow) {
        least_before_ = least_now_;
        least_now_ = UINT64_MAX;
        bucket_start_ = tick;
    }
    // Only acknowledged ages make the usual one: before the first, the age counts from
    // the first offer and says nothing of the round trip.
    least_now_ = acked ? std::min(least_now_, age) : least_now_;
    const std::uint64_t least = std::min(least_now_, least_before_);
    pace_ = age > unacked_window_               ? Pace::behind
            : acked && age > least + kLagMargin ? Pace::lagging
                                                : Pace::full;
    const std::uint64_t interval = pace_ == Pace::behind    ? kBehindInterval
                                   : pace_ == Pace::lagging ? kLaggingInterval
                                                            : 1;
    if (last_sent_ != 0 && tick - last_sent_ < interval) {
        ++(pace_ == Pace::behind ? skipped_behind_ : skipped_lagging_);
        return false;
    }
    last_sent_ = tick;
    return true;
}

} // namespace dsoc::server
