#include "dsoc/simclient/load_run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace dsoc::simclient {

namespace {

nlohmann::json summary_json(const common::Summary& s) {
    return {{"count", s.count}, {"mean", s.mean}, {"p50", s.p50},
            {"p95", s.p95},     {"p99", s.p99},   {"max", s.max}};
}

std::string join_counts(const std::map<std::string, std::uint64_t>& counts) {
    if (counts.empty()) {
        return "none";
    }
    std::string out;
    for (const auto& [k, v] : counts) {
        out += fmt::format("{}{}={}", out.empty() ? "" : " ", k, v);
    }
    return out;
}

} // namespace

std::string format_summary(const LoadReport& r) {
    return fmt::format(
        "simclient: {} clients against {}:{} for {:.1f} s ({})\n"
        "  connected              {}/{} ({} connect failures)\n"
        "  down per client        {:.1f} KiB/s ({:.0f} B/s), {:.0f} entity updates/s\n"
        "  up per client          {:.2f} KiB/s ({:.0f} B/s)\n"
        "  snapshots received     {}\n"
        "  entities known/client  mean {:.1f}  p95 {:.0f}\n"
        "  snapshot interarrival  p50 {:.1f} ms  p95 {:.1f} ms  p99 {:.1f} ms\n"
        "  round trip             p50 {:.2f} ms  p99 {:.2f} ms\n"
        "  replica audit          {} poses, max error {:.3f} quanta (limit 0.5)\n"
        "  protocol errors        {} ({})\n"
        "  unexpected disconnects {}; clients missing own entity {}\n"
        "  disconnect reasons     {}\n",
        r.clients, r.config.host, r.config.port, r.wall_seconds, r.passed() ? "PASS" : "FAIL",
        r.connected, r.clients, r.connect_failures, r.bytes_down_per_client_s / 1024.0,
        r.bytes_down_per_client_s, r.entity_updates_per_client_s, r.bytes_up_per_client_s / 1024.0,
        r.bytes_up_per_client_s, r.snapshots, r.entities_known.mean, r.entities_known.p95,
        r.snapshot_interarrival_ms.p50, r.snapshot_interarrival_ms.p95,
        r.snapshot_interarrival_ms.p99, r.rtt_ms.p50, r.rtt_ms.p99, r.audited_poses,
        r.max_audit_error, r.protocol_errors, join_counts(r.protocol_errors_by_kind),
        r.unexpected_disconnects, r.missing_own_entity, join_counts(r.disconnect_reasons));
}

std::string format_json(const LoadReport& r) {
    nlohmann::json j;
    j["passed"] = r.passed();
    j["server"] = fmt::format("{}:{}", r.config.host, r.config.port);
    j["clients"] = r.clients;
    j["duration_s"] = r.config.duration_s;
    j["ramp_up_s"] = r.config.ramp_up_s;
    j["wall_seconds"] = r.wall_seconds;
    j["connected"] = r.connected;
    j["connect_failures"] = r.connect_failures;
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
    j["audited_poses"] = r.audited_poses;
    j["max_audit_error_quanta"] = r.max_audit_error;
    j["entities_known_per_client"] = {{"mean", r.entities_known.mean},
                                      {"p95", r.entities_known.p95}};
    j["snapshot_interarrival_ms"] = summary_json(r.snapshot_interarrival_ms);
    j["rtt_ms"] = summary_json(r.rtt_ms);
    return j.dump(2);
}

} // namespace dsoc::simclient
