#include "dsoc/simclient/load_report.hpp"

#include "dsoc/simclient/sim_client.hpp"

#include <algorithm>
#include <set>
#include <utility>

namespace dsoc::simclient {

namespace {
/// A connected session that ran this long without seeing its own entity is missing it.
constexpr double kOwnEntityGraceS = 1.0;
} // namespace

LoadReport summarize_sessions(const std::vector<std::shared_ptr<SimClient>>& sessions) {
    LoadReport r;
    SampleHistogram known;
    SampleHistogram heard;
    SampleHistogram interarrival;
    SampleHistogram socket_interarrival;
    SampleHistogram handling_lag;
    SampleHistogram rtt;
    SampleHistogram connect;
    double down_rate_sum = 0.0;
    double up_rate_sum = 0.0;
    double update_rate_sum = 0.0;
    std::set<std::pair<std::string, int>> clients; // (group, index)
    for (const auto& c : sessions) {
        const ClientStats& s = c->stats();
        ++r.clients;
        const std::string group_name =
            c->setup().group != nullptr ? c->setup().group->name : "clients";
        GroupCounts& group = r.groups[group_name];
        group.clients += clients.emplace(group_name, c->setup().index).second ? 1 : 0;
        ++group.sessions;
        group.connected += s.hello_received ? 1 : 0;
        const bool failed = !s.failure.empty() && !s.failed_over;
        group.failures += failed ? 1 : 0;
        r.failovers += s.failed_over ? 1 : 0;
        if (s.hello_received) {
            ++r.connected;
            connect.add(s.connect_ms);
            if (!s.saw_own_entity && (s.snapshots > 0 || s.active_seconds >= kOwnEntityGraceS)) {
                ++r.missing_own_entity;
            }
            if (s.active_seconds > 0.0) {
                down_rate_sum += static_cast<double>(s.bytes_down) / s.active_seconds;
                up_rate_sum += static_cast<double>(s.bytes_up) / s.active_seconds;
                update_rate_sum += static_cast<double>(s.entity_updates) / s.active_seconds;
            }
        } else if (failed) {
            ++r.connect_failures;
        } else if (!s.failed_over) {
            ++r.cancelled_before_hello;
        }
        if (failed) {
            ++r.failures;
            ++r.failures_by_reason[s.failure];
            r.failure_examples.try_emplace(s.failure, c->name() + ": " + s.failure_detail);
        }
        r.unexpected_disconnects += s.unexpected_disconnect && !s.failed_over ? 1 : 0;
        if (!s.disconnect_reason.empty()) {
            ++r.disconnect_reasons[s.disconnect_reason];
        }
        for (const auto& [kind, n] : s.protocol_errors) {
            r.protocol_errors += n;
            r.protocol_errors_by_kind[kind] += n;
        }
        r.bytes_down += s.bytes_down;
        r.bytes_up += s.bytes_up;
        r.snapshots += s.snapshots;
        r.checked_snapshots += s.checks_snapshots ? s.snapshots : 0;
        r.entity_updates += s.entity_updates;
        r.audited_poses += s.audited_poses;
        r.max_audit_error = std::max(r.max_audit_error, s.max_audit_error);
        known.merge(s.known_samples);
        heard.merge(s.heard_samples);
        interarrival.merge(s.interarrival_ms);
        socket_interarrival.merge(s.socket_interarrival_ms);
        handling_lag.merge(s.handling_lag_ms);
        rtt.merge(s.rtt_ms);
    }
    if (r.connected > 0) {
        r.bytes_down_per_client_s = down_rate_sum / r.connected;
        r.bytes_up_per_client_s = up_rate_sum / r.connected;
        r.entity_updates_per_client_s = update_rate_sum / r.connected;
    }
    r.entities_known = known.summary();
    r.entities_heard = heard.summary();
    r.snapshot_interarrival_ms = interarrival.summary();
    r.snapshot_socket_interarrival_ms = socket_interarrival.summary();
    r.handling_lag_ms = handling_lag.summary();
    r.rtt_ms = rtt.summary();
    r.connect_ms = connect.summary();
    return r;
}

} // namespace dsoc::simclient
