#pragma once
// The server's end-of-run summary, as a readable block and as JSON.

#include "dsoc/server/server.hpp"

#include <string>

namespace dsoc::server {

/// Multi-line readable summary (ticks, tick cost p50/p99, bytes, disconnects).
std::string format_summary(const ServerStats& stats, const ServerConfig& config);

/// The same figures as a JSON object (keys: ticks, late_ticks, skipped_ticks,
/// cheapest_client_ticks, tick_cost_us {mean,
/// p50, p95, p99, max}, bytes_sent, bytes_received, snapshots_sent,
/// entity_updates_sent, clients_accepted, disconnects {reason: count}, policy, bots,
/// tick_rate).
std::string format_json(const ServerStats& stats, const ServerConfig& config);

} // namespace dsoc::server
