#pragma once
// What a load run measured, and whether it passed (docs/simclient.md, "Report keys").

#include "dsoc/common/percentiles.hpp"
#include "dsoc/simclient/load_config.hpp"
#include "dsoc/simclient/threshold.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dsoc::simclient {

/// Sessions of one client group.
struct GroupCounts {
    int clients = 0; ///< distinct clients (a respawner's sessions are one client)
    int sessions = 0;
    int connected = 0;
    std::uint64_t failures = 0;
};

struct LoadReport {
    LoadConfig config;
    double wall_seconds = 0.0;
    double scenario_seconds = 0.0; ///< the stages' length: the run ends there
    /// Sessions started (a client that respawns or churns starts another session);
    /// with the plain flags, the number of clients.
    int clients = 0;
    int connected = 0;        ///< sessions that got a server hello
    int peak_connected = 0;   ///< most sessions connected at one time (sampled each second)
    int connect_failures = 0; ///< sessions that failed before their server hello
    /// Sessions the run itself ended before their hello arrived (a ramp down, a churn
    /// or the run's end came first, within the connect timeout): neither connected nor
    /// failed.
    int cancelled_before_hello = 0;
    int unexpected_disconnects = 0;
    int missing_own_entity = 0; ///< connected sessions that never saw their own entity
    /// Sessions that failed, by reason (failure_reason.hpp: refused, timeout,
    /// unresolvable, unauthorized, version_mismatch, dropped_by_server, server_shutdown,
    /// connection_lost, connect_error, protocol_error); one reason per session.
    std::uint64_t failures = 0;
    /// Sessions that lost their server and were replaced at the next one
    /// (LoadConfig::more_servers); not failures.
    std::uint64_t failovers = 0;
    std::map<std::string, std::uint64_t> failures_by_reason;
    /// The first failure of each reason: "sim-0: connect to 127.0.0.1:1: Connection refused".
    std::map<std::string, std::string> failure_examples;
    /// Why the run ended before the scenario's end ("" when it did not): the server
    /// shut down, nothing could connect, or a signal.
    std::string stopped_early;
    std::uint64_t protocol_errors = 0;
    std::map<std::string, std::uint64_t> protocol_errors_by_kind;
    std::map<std::string, std::uint64_t> disconnect_reasons;
    std::uint64_t bytes_down = 0;
    std::uint64_t bytes_up = 0;
    std::uint64_t snapshots = 0;
    /// Of them, the ones decoded and checked (LoadConfig::check_every); the entity
    /// samples and the audits are of these.
    std::uint64_t checked_snapshots = 0;
    std::uint64_t entity_updates = 0;
    std::uint64_t audited_poses = 0;      ///< replica poses checked against the server's exact ones
    double max_audit_error = 0.0;         ///< [Units: quanta or angle steps] <= 0.5 when correct
    double bytes_down_per_client_s = 0.0; ///< mean over connected sessions of bytes / active s
    double bytes_up_per_client_s = 0.0;
    double entity_updates_per_client_s = 0.0;
    common::Summary entities_known;           ///< over every snapshot of every client
    common::Summary entities_heard;           ///< of them, known only by hearing (heard tier)
    common::Summary snapshot_interarrival_ms; ///< as the clients handled the snapshots
    /// Over UDP: as the snapshots reached the clients' sockets (ClientStats).
    common::Summary snapshot_socket_interarrival_ms;
    common::Summary handling_lag_ms; ///< over UDP: the load generator's own delay
    common::Summary rtt_ms;
    common::Summary connect_ms; ///< session start (resolve, TCP connect) to server hello
    std::map<std::string, GroupCounts> groups; ///< by group name
    std::vector<ThresholdResult> thresholds;

    /// Failed sessions over sessions that either connected or failed. [Units: fraction]
    [[nodiscard]] double failure_rate() const {
        const int decided = connected + connect_failures;
        return decided > 0 ? static_cast<double>(failures) / decided : 0.0;
    }
    [[nodiscard]] bool thresholds_passed() const {
        for (const auto& t : thresholds) {
            if (!t.passed) {
                return false;
            }
        }
        return true;
    }
    /// A load test gates on this: some session connected; no session failed (for any
    /// reason, an unexpected server shutdown included); no protocol error or unexpected
    /// disconnect; every connected session saw its own entity; every threshold held.
    [[nodiscard]] bool passed() const {
        return connected > 0 && connect_failures == 0 && failures == 0 && protocol_errors == 0 &&
               unexpected_disconnects == 0 && missing_own_entity == 0 && thresholds_passed();
    }
};

class SimClient;

/// The counts and figures of these sessions (not config, wall_seconds,
/// scenario_seconds, stopped_early or thresholds, which are the run's).
[[nodiscard]] LoadReport
summarize_sessions(const std::vector<std::shared_ptr<SimClient>>& sessions);

/// Readable multi-line summary.
std::string format_summary(const LoadReport& report);
/// The report as JSON (see docs/simclient.md for the keys).
std::string format_json(const LoadReport& report);

} // namespace dsoc::simclient
