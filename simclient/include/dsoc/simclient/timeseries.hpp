#pragma once
// The run second by second: what LoadRun measures each second, for the progress line
// on stderr and the --timeseries file (JSON lines, one object per second;
// docs/simclient.md, "Time series").

#include "dsoc/common/percentiles.hpp"

#include <cstdint>
#include <map>
#include <string>

namespace dsoc::simclient {

/// One interval of the run (a second; the last one may be shorter).
struct SecondSample {
    double t_s = 0.0;             ///< end of the interval, from the run's start [s]
    double interval_s = 0.0;      ///< its length [s]
    int target = 0;               ///< clients the stages ask for now
    int connected = 0;            ///< sessions connected now
    int connecting = 0;           ///< sessions resolving, connecting or awaiting their hello now
    std::uint64_t snapshots = 0;  ///< received in the interval, all clients
    std::uint64_t bytes_down = 0; ///< in the interval, all clients
    std::uint64_t bytes_up = 0;
    common::Summary interarrival_ms; ///< snapshot interarrivals that ended in the interval
    std::map<std::string, std::uint64_t> failures; ///< sessions that failed in the interval
    std::uint64_t failures_total = 0;              ///< since the start
    std::uint64_t protocol_errors_total = 0;       ///< since the start
};

/// "refused=2 timeout=1": counts by name, in name order; "" when empty.
[[nodiscard]] std::string join_counts(const std::map<std::string, std::uint64_t>& counts);

/// The sample as one line of JSON (no newline): t_s, target, connected, connecting,
/// snapshots_per_s, bytes_down_per_s, bytes_up_per_s, interarrival_p50_ms,
/// interarrival_p99_ms (null without samples), failures {reason: count},
/// failures_total, protocol_errors_total. Rates are over interval_s.
[[nodiscard]] std::string format_timeseries_line(const SecondSample& sample);

/// The progress line on stderr: "[  3.0s] clients 10/10 connected (target 10) | ...".
[[nodiscard]] std::string format_progress_line(const SecondSample& sample);

} // namespace dsoc::simclient
