#include "dsoc/server/stats_report.hpp"

#include "dsoc/common/percentiles.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace dsoc::server {

std::string format_summary(const ServerStats& stats, const ServerConfig& config) {
    const auto cost = common::summarize(stats.tick_cost_us);
    std::string out = fmt::format(
        "server: policy={} bots={} tick_rate={} Hz\n"
        "  ticks            {} ({} late, {} skipped; {} client-ticks over the culling budget)\n"
        "  tick cost        p50 {:.1f} us  p99 {:.1f} us  max {:.1f} us  (budget {:.0f} us)\n"
        "  sent             {} bytes, {} snapshots, {} entity updates\n"
        "  received         {} bytes from {} client(s)\n",
        interest::name_of(config.policy), config.bots, config.tick_rate, stats.ticks,
        stats.late_ticks, stats.skipped_ticks, stats.cheapest_client_ticks, cost.p50, cost.p99,
        cost.max, 1e6 / config.tick_rate, stats.bytes_sent, stats.snapshots_sent,
        stats.entity_updates_sent, stats.bytes_received, stats.clients_accepted);
    out += "  disconnects     ";
    if (stats.disconnects.empty()) {
        out += " none";
    }
    for (const auto& [reason, count] : stats.disconnects) {
        out += fmt::format(" {}={}", reason, count);
    }
    out += "\n";
    if (!stats.world_hop_us.empty()) {
        const auto hop = common::summarize(stats.world_hop_us);
        out += fmt::format("  world hop        p50 {:.1f} us  p99 {:.1f} us  max {:.1f} us  "
                           "(world tick encoded -> snapshots sent)\n",
                           hop.p50, hop.p99, hop.max);
    }
    return out;
}

std::string format_json(const ServerStats& stats, const ServerConfig& config) {
    const auto cost = common::summarize(stats.tick_cost_us);
    nlohmann::json j;
    j["policy"] = std::string(interest::name_of(config.policy));
    j["bots"] = config.bots;
    j["tick_rate"] = config.tick_rate;
    j["ticks"] = stats.ticks;
    j["late_ticks"] = stats.late_ticks;
    j["skipped_ticks"] = stats.skipped_ticks;
    j["cheapest_client_ticks"] = stats.cheapest_client_ticks;
    j["tick_cost_us"] = {{"mean", cost.mean},
                         {"p50", cost.p50},
                         {"p95", cost.p95},
                         {"p99", cost.p99},
                         {"max", cost.max}};
    j["bytes_sent"] = stats.bytes_sent;
    j["bytes_received"] = stats.bytes_received;
    j["snapshots_sent"] = stats.snapshots_sent;
    j["entity_updates_sent"] = stats.entity_updates_sent;
    j["clients_accepted"] = stats.clients_accepted;
    j["disconnects"] = stats.disconnects;
    if (!stats.world_hop_us.empty()) {
        const auto hop = common::summarize(stats.world_hop_us);
        j["world_hop_us"] = {
            {"mean", hop.mean}, {"p50", hop.p50}, {"p99", hop.p99}, {"max", hop.max}};
    }
    return j.dump(2);
}

} // namespace dsoc::server
