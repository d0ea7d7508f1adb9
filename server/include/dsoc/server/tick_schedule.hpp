#pragma once
// When the server's ticks are due: a fixed grid (no drift), except that a server
// that fell a whole period or more behind drops the ticks it missed instead of
// running them back to back - a burst of catch-up ticks would only delay every
// client further (and, after an overload, send hundreds of snapshots at once).
// Pure bookkeeping on time points, so the policy is tested without a clock.
//
// Threading: none; the server's tick thread.

#include <chrono>
#include <cstdint>

namespace dsoc::server {

class TickSchedule {
public:
    using Clock = std::chrono::steady_clock;

    /// The first tick is due at `start + period`. `period` > 0.
    TickSchedule(Clock::time_point start, Clock::duration period)
        : next_due_(start + period), period_(period) {}

    /// Before waiting for the next tick (after the previous one finished): when `now`
    /// is a whole period or more past the next due time, the missed ticks are dropped
    /// - the next due time moves forward by whole periods to the latest grid point not
    /// after `now`, so the next tick runs at once and the one after on the grid.
    /// Returns how many ticks were dropped (0 when on time).
    std::uint64_t skip_missed(Clock::time_point now) {
        if (now - next_due_ < period_) {
            return 0;
        }
        const auto missed = (now - next_due_) / period_;
        next_due_ += period_ * missed;
        skipped_just_now_ = true;
        return static_cast<std::uint64_t>(missed);
    }

    /// When the next tick is due.
    [[nodiscard]] Clock::time_point next_due() const { return next_due_; }

    /// A tick starts at `now`: moves on to the following one. Returns whether this tick
    /// is late - it started more than a period after it was due, or runs in place of
    /// ticks just dropped.
    bool start_tick(Clock::time_point now) {
        const bool late = skipped_just_now_ || now - next_due_ > period_;
        skipped_just_now_ = false;
        next_due_ += period_;
        return late;
    }

private:
    Clock::time_point next_due_;
    Clock::duration period_;
    bool skipped_just_now_ = false;
};

} // namespace dsoc::server
