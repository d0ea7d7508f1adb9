#include "dsoc/simclient/timeseries.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace dsoc::simclient {

namespace {
double per_s(std::uint64_t n, double seconds) {
    return seconds > 0.0 ? static_cast<double>(n) / seconds : 0.0;
}

/// To a tenth: the file is for reading and plotting, not for more digits than measured.
double tenth(double value) {
    return std::round(value * 10.0) / 10.0;
}
} // namespace

std::string join_counts(const std::map<std::string, std::uint64_t>& counts) {
    std::string out;
    for (const auto& [k, v] : counts) {
        out += fmt::format("{}{}={}", out.empty() ? "" : " ", k, v);
    }
    return out;
}

std::string format_timeseries_line(const SecondSample& s) {
    nlohmann::ordered_json j;
    j["t_s"] = std::round(s.t_s * 1000.0) / 1000.0;
    j["target"] = s.target;
    j["connected"] = s.connected;
    j["connecting"] = s.connecting;
    j["snapshots_per_s"] = tenth(per_s(s.snapshots, s.interval_s));
    j["bytes_down_per_s"] = tenth(per_s(s.bytes_down, s.interval_s));
    j["bytes_up_per_s"] = tenth(per_s(s.bytes_up, s.interval_s));
    if (s.interarrival_ms.count > 0) {
        j["interarrival_p50_ms"] = tenth(s.interarrival_ms.p50);
        j["interarrival_p99_ms"] = tenth(s.interarrival_ms.p99);
    } else {
        j["interarrival_p50_ms"] = nullptr;
        j["interarrival_p99_ms"] = nullptr;
    }
    j["failures"] = s.failures;
    j["failures_total"] = s.failures_total;
    j["protocol_errors_total"] = s.protocol_errors_total;
    return j.dump();
}

std::string format_progress_line(const SecondSample& s) {
    std::string failures = fmt::format("failures {}", s.failures_total);
    if (!s.failures.empty()) {
        failures += " (this second: " + join_counts(s.failures) + ")";
    }
    return fmt::format("[{:5.1f}s] clients {}/{} connected{} | snapshots/s {:.0f} | down {:.1f} "
                       "KiB/s | up {:.1f} KiB/s | {} | protocol errors {}",
                       s.t_s, s.connected, s.target,
                       s.connecting > 0 ? fmt::format(", {} connecting", s.connecting) : "",
                       per_s(s.snapshots, s.interval_s), per_s(s.bytes_down, s.interval_s) / 1024.0,
                       per_s(s.bytes_up, s.interval_s) / 1024.0, failures, s.protocol_errors_total);
}

} // namespace dsoc::simclient
