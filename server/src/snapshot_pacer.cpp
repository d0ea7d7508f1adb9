#include "dsoc/server/snapshot_pacer.hpp"

#include "dsoc/protocol/delta_frame.hpp"

#include <algorithm>
#include <cassert>

namespace dsoc::server {

SnapshotPacer::SnapshotPacer(int tick_rate)
    : unacked_window_(unacked_window_at(tick_rate)),
      base_window_(std::max<std::uint64_t>(64, static_cast<std::uint64_t>(kBaseWindowSeconds) *
                                                   static_cast<std::uint64_t>(tick_rate))) {}

std::uint64_t SnapshotPacer::unacked_window_at(int tick_rate) {
    return std::clamp<std::uint64_t>((static_cast<std::uint64_t>(tick_rate) + 1) / 2, 8,
                                     protocol::kAckedHistory - 1 - kBehindInterval);
}

bool SnapshotPacer::offer(std::uint64_t tick, std::optional<std::uint64_t> acked) {
    assert(tick > last_offered_);
    // A client acknowledges only snapshots it was sent, all of earlier ticks.
    const bool acked_earlier = acked && *acked < tick;
    assert(!acked || acked_earlier);
    if (first_tick_ == 0) {
        first_tick_ = tick;
    }
    const std::uint64_t since = acked_earlier ? *acked : first_tick_;
    const std::uint64_t age = tick > since ? tick - since : 0;
    if (last_offered_ == 0 || tick - last_offered_ >= 2 * base_window_) {
        // The first offer, or none for two windows (a client without an entity is not
        // offered snapshots): what was least then says nothing now.
        least_now_ = UINT64_MAX;
        least_before_ = UINT64_MAX;
        bucket_start_ = tick;
    } else if (tick - bucket_start_ >= base_window_) {
        least_before_ = least_now_;
        least_now_ = UINT64_MAX;
        bucket_start_ = tick;
    }
    last_offered_ = tick;
    // Only acknowledged ages make the usual one: before the first, the age counts from
    // the first offer and says nothing of the round trip.
    least_now_ = acked_earlier ? std::min(least_now_, age) : least_now_;
    const std::uint64_t least = std::min(least_now_, least_before_); // <= age when acked
    pace_ = age > unacked_window_                       ? Pace::behind
            : acked_earlier && age - least > kLagMargin ? Pace::lagging
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
