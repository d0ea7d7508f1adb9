#include "dsoc/simclient/load_report.hpp"
#include "dsoc/simclient/timeseries.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace dsoc::simclient {

namespace {

nlohmann::json summary_json(const common::Summary& s) {
    return {{"count", s.count}, {"mean", s.mean}, {"p50", s.p50},
            {"p95", s.p95},     {"p99", s.p99},   {"max", s.max}};
}

/// join_counts(), or "none".
std::string counts_or_none(const std::map<std::string, std::uint64_t>& counts) {
    return counts.empty() ? "none" : join_counts(counts);
}

/// Why the run failed, one phrase per cause; empty when it passed.
std::vector<std::string> fail_causes(const LoadReport& r) {
    std::vector<std::string> causes;
    if (!r.stopped_early.empty() && r.failures > 0) {
        causes.push_back("stopped early: " + r.stopped_early);
    }
    if (r.connected == 0) {
        causes.emplace_back("no session connected");
    }
    if (r.failures > 0) {
        causes.push_back(fmt::format("{} session(s) failed ({})", r.failures,
                                     counts_or_none(r.failures_by_reason)));
    }
    if (r.protocol_errors > 0) {
        causes.push_back(fmt::format("{} protocol error(s)", r.protocol_errors));
    }
    if (r.unexpected_disconnects > 0) {
        causes.push_back(fmt::format("{} unexpected disconnect(s)", r.unexpected_disconnects));
    }
    if (r.missing_own_entity > 0) {
        causes.push_back(
            fmt::format("{} session(s) never saw their own entity", r.missing_own_entity));
    }
    for (const auto& t : r.thresholds) {
        if (!t.passed) {
            causes.push_back("threshold failed: " + describe(t));
        }
    }
    return causes;
}

} // namespace

std::string format_summary(const LoadReport& r) {
    std::string out = fmt::format(
        "simclient: {} sessions against {}:{} for {:.1f} s of {:.1f} s ({})\n"
        "  connected              {}/{} (peak {} at once; {} connect failures, {} cancelled "
        "before hello)\n"
        "  connect time           p50 {:.1f} ms  p99 {:.1f} ms\n"
        "  down per client        {:.1f} KiB/s ({:.0f} B/s), {:.0f} entity updates/s\n"
        "  up per client          {:.2f} KiB/s ({:.0f} B/s)\n"
        "  snapshots received     {} ({} decoded and checked)\n"
        "  entities known/client  mean {:.1f}  p95 {:.0f}; by hearing only mean {:.1f}\n"
        "  snapshot interarrival  p50 {:.1f} ms  p95 {:.1f} ms  p99 {:.1f} ms\n",
        r.clients, r.config.host, r.config.port, r.wall_seconds, r.scenario_seconds,
        r.passed() ? "PASS" : "FAIL", r.connected, r.clients, r.peak_connected, r.connect_failures,
        r.cancelled_before_hello, r.connect_ms.p50, r.connect_ms.p99,
        r.bytes_down_per_client_s / 1024.0, r.bytes_down_per_client_s,
        r.entity_updates_per_client_s, r.bytes_up_per_client_s / 1024.0, r.bytes_up_per_client_s,
        r.snapshots, r.checked_snapshots, r.entities_known.mean, r.entities_known.p95,
        r.entities_heard.mean, r.snapshot_interarrival_ms.p50, r.snapshot_interarrival_ms.p95,
        r.snapshot_interarrival_ms.p99);
    if (r.snapshot_socket_interarrival_ms.count > 0) {
        out += fmt::format(
            "    at the sockets       p50 {:.1f} ms  p95 {:.1f} ms  p99 {:.1f} ms; "
            "handling lag p50 {:.1f} ms  p99 {:.1f} ms\n",
            r.snapshot_socket_interarrival_ms.p50, r.snapshot_socket_interarrival_ms.p95,
            r.snapshot_socket_interarrival_ms.p99, r.handling_lag_ms.p50, r.handling_lag_ms.p99);
    }
    out += fmt::format(
        "  round trip             p50 {:.2f} ms  p99 {:.2f} ms\n"
        "  replica audit          {} poses, max error {:.3f} quanta (limit 0.5)\n"
        "  protocol errors        {} ({})\n"
        "  unexpected disconnects {}; clients missing own entity {}\n"
        "  disconnect reasons     {}\n"
        "  failures               {} ({})\n",
        r.rtt_ms.p50, r.rtt_ms.p99, r.audited_poses, r.max_audit_error, r.protocol_errors,
        counts_or_none(r.protocol_errors_by_kind), r.unexpected_disconnects, r.missing_own_entity,
        counts_or_none(r.disconnect_reasons), r.failures, counts_or_none(r.failures_by_reason));
    for (const auto& [reason, example] : r.failure_examples) {
        out += fmt::format("    {:<20} first: {}\n", reason, example);
    }
    if (r.failovers > 0 || !r.config.more_servers.empty()) {
        out += fmt::format("  failovers              {} (sessions that lost their server, each "
                           "replaced at the next of {} servers)\n",
                           r.failovers, 1 + r.config.more_servers.size());
    }
    if (!r.groups.empty()) {
        out += "  groups                ";
        for (const auto& [name, g] : r.groups) {
            out += fmt::format(" {}: {} clients, {} sessions, {} connected, {} failed;", name,
                               g.clients, g.sessions, g.connected, g.failures);
        }
        out.back() = '\n';
    }
    if (!r.stopped_early.empty()) {
        out += "  stopped early          " + r.stopped_early + "\n";
    }
    if (!r.thresholds.empty()) {
        int failed = 0;
        for (const auto& t : r.thresholds) {
            failed += t.passed ? 0 : 1;
        }
        out += fmt::format("  thresholds             {} passed, {} failed\n",
                           static_cast<int>(r.thresholds.size()) - failed, failed);
        for (const auto& t : r.thresholds) {
            out += fmt::format("    {} {}\n", t.passed ? "pass" : "FAIL", describe(t));
        }
    }
    const auto causes = fail_causes(r);
    if (r.passed()) {
        out += "PASS\n";
    } else {
        out += "FAIL:";
        for (std::size_t i = 0; i < causes.size(); ++i) {
            out += (i == 0 ? " " : "; ") + causes[i];
        }
        out += "\n";
    }
    return out;
}

std::string format_json(const LoadReport& r) {
    nlohmann::json j;
    j["passed"] = r.passed();
    j["fail_causes"] = fail_causes(r);
    j["server"] = fmt::format("{}:{}", r.config.host, r.config.port);
    j["clients"] = r.clients;
    j["scenario_seconds"] = r.scenario_seconds;
    j["duration_s"] = r.scenario_seconds;
    j["ramp_up_s"] = r.config.scenario ? 0.0 : r.config.ramp_up_s;
    j["wall_seconds"] = r.wall_seconds;
    j["stopped_early"] = r.stopped_early;
    j["connected"] = r.connected;
    j["peak_connected"] = r.peak_connected;
    j["connect_failures"] = r.connect_failures;
    j["cancelled_before_hello"] = r.cancelled_before_hello;
    j["failures"] = r.failures;
    j["failovers"] = r.failovers;
    j["failures_by_reason"] = r.failures_by_reason;
    j["failure_examples"] = r.failure_examples;
    j["failure_rate"] = r.failure_rate();
    j["protocol_errors"] = r.protocol_errors;
    j["protocol_errors_by_kind"] = r.protocol_errors_by_kind;
    j["unexpected_disconnects"] = r.unexpected_disconnects;
    j["missing_own_entity"] = r.missing_own_entity;
    j["disconnect_reasons"] = r.disconnect_reasons;
    j["bytes_down_total"] = r.bytes_down;
    j["bytes_up_total"] = r.bytes_up;
    j["bytes_down_per_client_per_s"] = r.bytes_down_per_client_s;
    j["bytes_up_per_client_per_s"] = r.bytes_up_per_client_s;
    j["entity_updates_per_client_per_s"] = r.entity_updates_per_client_s;
    j["snapshots_received"] = r.snapshots;
    j["snapshots_checked"] = r.checked_snapshots;
    j["audited_poses"] = r.audited_poses;
    j["max_audit_error_quanta"] = r.max_audit_error;
    j["entities_known_per_client"] = {{"mean", r.entities_known.mean},
                                      {"p95", r.entities_known.p95}};
    j["entities_heard_per_client"] = {{"mean", r.entities_heard.mean},
                                      {"p95", r.entities_heard.p95}};
    j["snapshot_interarrival_ms"] = summary_json(r.snapshot_interarrival_ms);
    j["snapshot_socket_interarrival_ms"] = summary_json(r.snapshot_socket_interarrival_ms);
    j["handling_lag_ms"] = summary_json(r.handling_lag_ms);
    j["rtt_ms"] = summary_json(r.rtt_ms);
    j["connect_ms"] = summary_json(r.connect_ms);
    j["groups"] = nlohmann::json::object();
    for (const auto& [name, g] : r.groups) {
        j["groups"][name] = {{"clients", g.clients},
                             {"sessions", g.sessions},
                             {"connected", g.connected},
                             {"failures", g.failures}};
    }
    j["thresholds"] = nlohmann::json::array();
    for (const auto& t : r.thresholds) {
        const double per_unit = t.threshold.limit.per_unit;
        j["thresholds"].push_back(
            {{"threshold", t.threshold.text},
             {"figure", t.threshold.figure},
             {"operator", std::string(to_string(t.threshold.comparison))},
             {"limit", t.threshold.limit.base / per_unit},
             {"unit", t.threshold.limit.unit},
             {"observed", t.has_value ? nlohmann::json(t.observed / per_unit) : nlohmann::json()},
             {"passed", t.passed}});
    }
    return j.dump(2);
}

} // namespace dsoc::simclient
