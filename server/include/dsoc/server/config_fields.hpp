#pragma once
// The one list of ServerConfig's fields by their TOML name. The config file loader,
// --print-config and the tests walk it, so a new setting is one line here. All are
// flat keys except `dsoc`, the [dsoc] table (dsoc_settings.hpp).

#include "dsoc/server/server_config.hpp"

namespace dsoc::server {

/// Calls `visit(name, field)` for every field of `config`, in the order of
/// server_config.hpp. `Config` is ServerConfig or const ServerConfig.
template <class Config, class Visitor>
void visit_config_fields(Config& config, Visitor&& visit) {
    visit("role", config.role);
    visit("nats_url", config.nats_url);
    visit("world_name", config.world_name);
    visit("bind_address", config.bind_address);
    visit("port", config.port);
    visit("tick_rate", config.tick_rate);
    visit("bots", config.bots);
    visit("teams", config.teams);
    visit("sounds", config.sounds);
    visit("footstep_range", config.footstep_range);
    visit("shot_range", config.shot_range);
    visit("bot_shots_per_second", config.bot_shots_per_second);
    visit("shot_damage", config.shot_damage);
    visit("map", config.map);
    visit("policy", config.policy);
    visit("tbv_strategy", config.tbv_strategy);
    visit("culler", config.culler);
    visit("portal_depth", config.portal_depth);
    visit("pvs_stage", config.pvs_stage);
    visit("baked_stage", config.baked_stage);
    visit("bake_cell_size", config.bake_cell_size);
    visit("bake_dir", config.bake_dir);
    visit("exact_stages", config.exact_stages);
    visit("culling_budget", config.culling_budget);
    visit("region_reuse_margin", config.region_reuse_margin);
    visit("latency_allowance_ms", config.latency_allowance_ms);
    visit("trace_file", config.trace_file);
    visit("trace_every", config.trace_every);
    visit("distance_radius", config.distance_radius);
    visit("threads", config.threads);
    visit("position_quantum_near", config.position_quantum_near);
    visit("position_quantum_mid", config.position_quantum_mid);
    visit("position_quantum_far", config.position_quantum_far);
    visit("angle_steps", config.angle_steps);
    visit("heard_quantum", config.heard_quantum);
    visit("network_lod", config.network_lod);
    visit("max_clients", config.max_clients);
    visit("max_pending_connections", config.max_pending_connections);
    visit("max_pending_per_source", config.max_pending_per_source);
    visit("max_frame_bytes", config.max_frame_bytes);
    visit("max_send_queue_bytes", config.max_send_queue_bytes);
    visit("handshake_timeout_ms", config.handshake_timeout_ms);
    visit("udp", config.udp);
    visit("udp_timeout_ms", config.udp_timeout_ms);
    visit("udp_handshake_rate", config.udp_handshake_rate);
    visit("udp_challenge_rate", config.udp_challenge_rate);
    visit("heap_metrics", config.heap_metrics);
    visit("slow_client_timeout_ms", config.slow_client_timeout_ms);
    visit("socket_send_buffer_bytes", config.socket_send_buffer_bytes);
    visit("io_gather_us", config.io_gather_us);
    visit("max_inputs_per_second", config.max_inputs_per_second);
    visit("insecure", config.insecure);
    visit("token_key_file", config.token_key_file);
    visit("metrics_port", config.metrics_port);
    visit("metrics_bind_address", config.metrics_bind_address);
    visit("log_level", config.log_level);
    visit("log_format", config.log_format);
    visit("max_speed", config.max_speed);
    visit("seed", config.seed);
    visit("duration_s", config.duration_s);
    visit("dsoc", config.dsoc); // the [dsoc] table (dsoc_settings.hpp), printed last
}

} // namespace dsoc::server
