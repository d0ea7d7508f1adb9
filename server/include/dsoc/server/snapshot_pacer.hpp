#pragma once
// Which ticks a UDP client is sent a snapshot, from how old its newest acknowledgement
// is when the tick's snapshots are built (delay-based congestion control, as LEDBAT
// judges a link by its delay above the least it has seen).
//
// A client that reads (or a network that carries) snapshots slower than they are sent
// shows it first in its acknowledgements, which age. Sent at full rate, each snapshot
// would be coded against an ever older baseline, larger and dearer at both ends, until
// the baseline left the history and every snapshot went whole: a load that feeds itself
// (a load generator sharing the server's cores showed it). So the pace steps down:
// - full: every tick;
// - lagging, the acknowledgement more than kLagMargin ticks older than the least age this
//   client's acknowledgements showed over the last base_window() to 2 base_window()
//   ticks, 10 to 20 s (its usual round trip, so a player far away is not slowed for the
//   distance): every kLaggingInterval-th tick, which halves the work and still keeps
//   snapshots two ticks apart. Only acknowledged ages count, so a client that has
//   acknowledged nothing yet is never lagging, only behind. The window is long enough
//   that a lag lasting seconds does not become the usual age (with a window of a few
//   seconds, the server's own overload did, and the client went back to full rate while
//   it still lagged), and short enough that a round trip that grew for good is the
//   usual one within 20 s;
// - behind, the acknowledgement (or, before any, the first snapshot offered) older than
//   the unacked window (half a second of ticks, 8 to 27): every kBehindInterval-th tick;
//   the snapshots still sent keep acknowledgements moving when the earlier ones were
//   lost.
// Each pace holds until the age falls back under its threshold.
//
// Threading: none; one per connection, used on the server's tick thread.

#include <cstdint>
#include <optional>

namespace dsoc::server {

class SnapshotPacer {
public:
    enum class Pace { full, lagging, behind };

    /// `tick_rate` in Hz (> 0).
    explicit SnapshotPacer(int tick_rate);

    /// Whether the client gets the snapshot of `tick` (greater than the last call's);
    /// `acked`: its newest acknowledged tick, if any (earlier than `tick`: only snapshots
    /// sent are acknowledged).
    [[nodiscard]] bool offer(std::uint64_t tick, std::optional<std::uint64_t> acked);
    /// The pace of the last offer().
    [[nodiscard]] Pace pace() const { return pace_; }
    /// Ticks the client was not offered, by pace.
    [[nodiscard]] std::uint64_t skipped_lagging() const { return skipped_lagging_; }
    [[nodiscard]] std::uint64_t skipped_behind() const { return skipped_behind_; }
    /// How old the newest acknowledgement may be before the client is behind: half a second
    /// of ticks (round trips of real players stay well within it), at least 8 and at most
    /// kAckedHistory - 1 - kBehindInterval (27), so that the first snapshot sent behind is
    /// still coded against the acknowledged frame (above 54 Hz the cap makes the window
    /// shorter than half a second). [Units: ticks]
    [[nodiscard]] std::uint64_t unacked_window() const { return unacked_window_; }
    [[nodiscard]] static std::uint64_t unacked_window_at(int tick_rate);

    /// A lagging client gets a snapshot every this many ticks. [Units: ticks]
    static constexpr std::uint64_t kLaggingInterval = 2;
    /// A client behind gets a snapshot every this many ticks. [Units: ticks]
    static constexpr std::uint64_t kBehindInterval = 4;
    /// How much older than its least recent age an acknowledgement may be before the
    /// client is lagging: more than a jitter of a tick or two, or a lost input whose
    /// acknowledgement the next one repeats. [Units: ticks]
    static constexpr std::uint64_t kLagMargin = 3;
    /// Over how many ticks the least age is taken: two buckets of this length, each
    /// kBaseWindowSeconds of ticks (at least 64). [Units: ticks]
    [[nodiscard]] std::uint64_t base_window() const { return base_window_; }
    static constexpr int kBaseWindowSeconds = 10;

private:
    std::uint64_t unacked_window_;
    std::uint64_t first_tick_ = 0; ///< 0: nothing offered yet
    std::uint64_t last_offered_ = 0;
    std::uint64_t last_sent_ = 0;
    std::uint64_t base_window_;
    // The least age seen in the current bucket of base_window_ ticks and in the one before.
    std::uint64_t bucket_start_ = 0;
    std::uint64_t least_now_ = UINT64_MAX;
    std::uint64_t least_before_ = UINT64_MAX;
    Pace pace_ = Pace::full;
    std::uint64_t skipped_lagging_ = 0;
    std::uint64_t skipped_behind_ = 0;
};

} // namespace dsoc::server
