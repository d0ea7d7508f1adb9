#include "dsoc/server/server_config.hpp"

#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/server/dsoc_settings.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <string>

namespace dsoc::server {

namespace {

void check(std::vector<std::string>& problems, bool ok, const char* field, const std::string& why) {
    if (!ok) {
        problems.push_back(std::string(field) + ": " + why);
    }
}

/// An integer setting within [lo, hi]; else "<field>: must be lo..hi<unit>, got <value>".
void check_range(std::vector<std::string>& problems, const char* field, std::int64_t value,
                 std::int64_t lo, std::int64_t hi, const char* unit = "") {
    check(problems, value >= lo && value <= hi, field,
          "must be " + std::to_string(lo) + ".." + std::to_string(hi) + unit + ", got " +
              std::to_string(value));
}

} // namespace

std::vector<std::string> validate(const ServerConfig& c) {
    std::vector<std::string> p;
    check(p, c.role == "single" || c.role == "world" || c.role == "gateway", "role",
          "must be one of single, world, gateway; got '" + c.role + "'");
    check(p, c.role == "single" || !c.nats_url.empty(), "nats_url",
          "must name a NATS server for role " + c.role);
    check(p,
          !c.world_name.empty() && c.world_name.size() <= 64 &&
              std::all_of(c.world_name.begin(), c.world_name.end(),
                          [](char ch) {
                              return std::isalnum(static_cast<unsigned char>(ch)) != 0 ||
                                     ch == '-' || ch == '_';
                          }),
          "world_name",
          "must be 1..64 letters, digits, '-' or '_' (it is part of NATS subjects); got '" +
              c.world_name + "'");
    check(p, !c.bind_address.empty(), "bind_address", "must not be empty");
    check_range(p, "tick_rate", c.tick_rate, 1, kMaxTickRate, " Hz");
    check_range(p, "bots", c.bots, 0, 100000);
    check_range(p, "teams", c.teams, 0, 1000);
    for (const auto& [name, range] :
         {std::pair{"footstep_range", c.footstep_range}, std::pair{"shot_range", c.shot_range}}) {
        check(p, std::isfinite(range) && range >= 0.0f && range <= 100000.0f, name,
              "must be 0..100000 world units, got " + std::to_string(range));
    }
    check(p,
          std::isfinite(c.bot_shots_per_second) && c.bot_shots_per_second >= 0.0f &&
              c.bot_shots_per_second <= 100.0f,
          "bot_shots_per_second",
          "must be 0..100 per second, got " + std::to_string(c.bot_shots_per_second));
    check_range(p, "shot_damage", c.shot_damage, 0, sim::kMaxHealth);
    check(p,
          c.tbv_strategy == "adaptive" || c.tbv_strategy == "explicit" || c.tbv_strategy == "fuzzy",
          "tbv_strategy", "must be one of adaptive, explicit, fuzzy; got '" + c.tbv_strategy + "'");
    check(p, c.portal_depth >= 0 && c.portal_depth <= visibility::ShaftOcclusion::kMaxPortalDepth,
          "portal_depth", "must be 0..4, got " + std::to_string(c.portal_depth));
    check(p,
          std::isfinite(c.bake_cell_size) && c.bake_cell_size >= 4.0f &&
              c.bake_cell_size <= 1024.0f,
          "bake_cell_size", "must be 4..1024 units");
    check(p, std::isfinite(c.culling_budget) && c.culling_budget >= 0.0 && c.culling_budget <= 1.0,
          "culling_budget", "must be 0..1 (a share of the tick period; 0 = off)");
    check(p,
          std::isfinite(c.region_reuse_margin) && c.region_reuse_margin >= 0.0f &&
              c.region_reuse_margin <= 512.0f,
          "region_reuse_margin", "must be 0..512 units");
    check_range(p, "latency_allowance_ms", c.latency_allowance_ms, 0, 2000, " ms");
    check(p, c.trace_every >= 1, "trace_every", "must be >= 1");
    check(p, std::isfinite(c.distance_radius) && c.distance_radius > 0.0f, "distance_radius",
          "must be a finite number > 0");
    check_range(p, "max_clients", c.max_clients, 1, 100000);
    check_range(p, "max_pending_connections", c.max_pending_connections, 1, 1000000);
    check_range(p, "max_pending_per_source", c.max_pending_per_source, 1, 1000000);
    check_range(p, "max_frame_bytes", c.max_frame_bytes, 64, 16 * 1024 * 1024);
    check(p, c.max_send_queue_bytes >= c.max_frame_bytes, "max_send_queue_bytes",
          "must be at least max_frame_bytes");
    check(p, c.handshake_timeout_ms > 0, "handshake_timeout_ms", "must be > 0");
    check_range(p, "udp_timeout_ms", c.udp_timeout_ms, 500, 60000, " ms");
    check_range(p, "udp_handshake_rate", c.udp_handshake_rate, 1, 1000000, " per second");
    check_range(p, "udp_challenge_rate", c.udp_challenge_rate, 1, 1000000, " per second");
    check(p, c.threads >= 0 && c.threads <= 256, "threads",
          "must be 0 (one per core)..256, got " + std::to_string(c.threads));
    for (auto& problem : protocol::validate(quantization(c))) {
        p.push_back(std::move(problem));
    }
    check_range(p, "io_gather_us", c.io_gather_us, 0, 20000, " µs");
    // Timers fire up to a gather late (io_loop.hpp): the tick's must stay well within
    // its period.
    check(p,
          c.tick_rate <= 0 ||
              static_cast<std::int64_t>(c.io_gather_us) * c.tick_rate * 4 <= 1'000'000,
          "io_gather_us",
          "must be at most a quarter of the tick period (" +
              std::to_string(250'000 / std::max(1, c.tick_rate)) + " µs at " +
              std::to_string(c.tick_rate) + " Hz), got " + std::to_string(c.io_gather_us));
    check_range(p, "slow_client_timeout_ms", c.slow_client_timeout_ms, 100, 60000, " ms");
    check(p,
          c.socket_send_buffer_bytes == 0 ||
              (c.socket_send_buffer_bytes >= 4096 && c.socket_send_buffer_bytes <= 16 << 20),
          "socket_send_buffer_bytes",
          "must be 0 (OS default) or 4096..16777216, got " +
              std::to_string(c.socket_send_buffer_bytes));
    check_range(p, "max_inputs_per_second", c.max_inputs_per_second, 1, 10000, " per second");
    check(p, c.max_inputs_per_second >= c.tick_rate + 2, "max_inputs_per_second",
          "must be at least tick_rate + 2 (an honest client sends one input per tick and a "
          "ping a second), got " +
              std::to_string(c.max_inputs_per_second));
    // The world role takes no clients, so it needs no key.
    check(p, c.insecure || c.role == "world" || !c.token_key_file.empty(), "token_key_file",
          "required unless insecure = true (mint a key with dsoc-token keygen)");
    check(p, c.metrics_port >= -1 && c.metrics_port <= 65535, "metrics_port",
          "must be -1 (off), 0 (any free port) or 1..65535, got " + std::to_string(c.metrics_port));
    check(p, c.metrics_port == -1 || !c.metrics_bind_address.empty(), "metrics_bind_address",
          "must not be empty when metrics_port is set");
    check(p,
          c.log_level == "trace" || c.log_level == "debug" || c.log_level == "info" ||
              c.log_level == "warn" || c.log_level == "error" || c.log_level == "critical" ||
              c.log_level == "off",
          "log_level",
          "must be one of trace, debug, info, warn, error, critical, off; got '" + c.log_level +
              "'");
    check(p, c.log_format == "text" || c.log_format == "json", "log_format",
          "must be text or json; got '" + c.log_format + "'");
    check(p, c.seed <= static_cast<std::uint64_t>(INT64_MAX), "seed",
          "must be at most 2^63-1 (a TOML integer)");
    check(p, std::isfinite(c.max_speed) && c.max_speed > 0.0f, "max_speed",
          "must be a finite number > 0");
    check(p, !c.map.empty(), "map", "must name a map");
    check(p, std::isfinite(c.duration_s) && c.duration_s >= 0.0, "duration_s", "must be >= 0");
    for (auto& problem : validate_dsoc_settings(c)) {
        p.push_back(std::move(problem));
    }
    return p;
}

protocol::QuantizationSettings quantization(const ServerConfig& c) {
    protocol::QuantizationSettings q;
    q.position_quantum = {c.position_quantum_near, c.position_quantum_mid, c.position_quantum_far};
    q.angle_steps = c.angle_steps;
    q.heard_quantum = c.heard_quantum;
    return q;
}

int lookahead_ticks(const ServerConfig& c) {
    return interest::lookahead_ticks(c.latency_allowance_ms, c.tick_rate);
}

} // namespace dsoc::server
