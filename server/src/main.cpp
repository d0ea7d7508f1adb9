// dsoc-server: the game server with occlusion-aware interest management.

#include "dsoc/maps/map_checks.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/server/config_file.hpp"
#include "dsoc/server/dsoc_settings.hpp"
#include "dsoc/server/metrics_endpoint.hpp"
#include "dsoc/server/server.hpp"
#include "dsoc/server/stats_report.hpp"

#include "program_options.hpp"

#include <CLI/CLI.hpp>
#include <boost/asio/signal_set.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

struct ProgramOptions {
    std::string config_file;
    std::string stats_json;
    bool print_config = false;
    std::vector<std::string> dsoc; ///< --dsoc KEY=VALUE, in order
};

/// Every flag, bound to `config` and `options`. Flags given on the command line
/// overwrite what the config file set.
void add_options(CLI::App& app, dsoc::server::ServerConfig& config, ProgramOptions& options) {
    app.add_option("--config", options.config_file,
                   "TOML file with settings (keys as in --print-config); flags override it");
    app.add_flag("--print-config", options.print_config,
                 "Print the effective settings as TOML and exit (2 when they are invalid)");
    app.add_option("--bind", config.bind_address, "Address to listen on")->capture_default_str();
    app.add_option("--port", config.port, "TCP port; 0 picks a free one")->capture_default_str();
    dsoc::server::add_world_options(app, config);
    dsoc::server::add_policy_options(app, config);
    app.add_option("--tbv-strategy", config.tbv_strategy, "dsoc TBVs: adaptive | explicit | fuzzy")
        ->capture_default_str();
    app.add_option("--culler", config.culler, "Occlusion culler stages: shaft | pyramid | both")
        ->capture_default_str();
    app.add_option("--culling-budget", config.culling_budget,
                   "Share of the tick period for culling; clients after it get the cheapest "
                   "conservative answer (0 = off)")
        ->capture_default_str();
    app.add_option("--pvs-stage", config.pvs_stage,
                   "Reject with the map's PVS before the culler (true/false)")
        ->capture_default_str();
    app.add_option("--region-margin", config.region_reuse_margin,
                   "dsoc: reuse a client's culler region within this margin [units]")
        ->capture_default_str();
    app.add_option("--latency-allowance-ms", config.latency_allowance_ms,
                   "Client movement the server covers: RTT + interpolation delay [ms]")
        ->capture_default_str();
    app.add_option("--trace", config.trace_file, "Write a replication trace (JSON Lines) here");
    app.add_option("--trace-every", config.trace_every, "Record every k-th tick in the trace")
        ->capture_default_str();
    app.add_option("--distance-radius", config.distance_radius,
                   "Radius of the distance policy [units]")
        ->capture_default_str();
    app.add_option("--threads", config.threads,
                   "Worker threads for the per-client tick work, beside the I/O thread; 0: one "
                   "per core")
        ->capture_default_str();
    app.add_option("--position-quantum-near", config.position_quantum_near,
                   "Snapshot position precision, entities updated every tick [units]")
        ->capture_default_str();
    app.add_option("--position-quantum-mid", config.position_quantum_mid,
                   "Snapshot position precision, entities updated every 2nd tick [units]")
        ->capture_default_str();
    app.add_option("--position-quantum-far", config.position_quantum_far,
                   "Snapshot position precision, entities updated every 4th tick [units]")
        ->capture_default_str();
    app.add_option("--angle-steps", config.angle_steps, "Snapshot angle steps per full turn")
        ->capture_default_str();
    app.add_option("--network-lod", config.network_lod,
                   "Coarser, rarer updates for distant entities (dsoc/occlusion) (true/false)")
        ->capture_default_str();
    app.add_option("--max-clients", config.max_clients, "Connected clients at most")
        ->capture_default_str();
    app.add_option("--max-frame-bytes", config.max_frame_bytes,
                   "Largest frame a client may send [bytes]")
        ->capture_default_str();
    app.add_option("--max-send-queue-bytes", config.max_send_queue_bytes,
                   "Unsent bytes per client before it is dropped as too slow")
        ->capture_default_str();
    app.add_option("--handshake-timeout-ms", config.handshake_timeout_ms,
                   "Close connections that send no hello within this time [ms]")
        ->capture_default_str();
    app.add_option("--max-speed", config.max_speed, "Speed bound of every entity [units/s]")
        ->capture_default_str();
    app.add_option("--duration", config.duration_s,
                   "Stop after this many seconds (0: run until signalled)")
        ->capture_default_str();
    app.add_option("--slow-client-timeout-ms", config.slow_client_timeout_ms,
                   "Disconnect a client whose snapshot stays unsent this long [ms]")
        ->capture_default_str();
    app.add_option("--socket-send-buffer-bytes", config.socket_send_buffer_bytes,
                   "SO_SNDBUF of client sockets; 0 keeps the OS default [bytes]")
        ->capture_default_str();
    app.add_option("--max-inputs-per-second", config.max_inputs_per_second,
                   "Messages a client may send per second; more are dropped, twice that "
                   "disconnects")
        ->capture_default_str();
    app.add_flag("--insecure", config.insecure,
                 "Accept clients without connect tokens (local tests and demos only)");
    app.add_option("--token-key-file", config.token_key_file,
                   "Connect-token key file (64 hex digits; dsoc-token keygen makes one)");
    app.add_option("--metrics-port", config.metrics_port,
                   "Serve Prometheus /metrics on this port (-1 off, 0 any free port)")
        ->capture_default_str();
    app.add_option("--metrics-bind", config.metrics_bind_address, "Address of the metrics endpoint")
        ->capture_default_str();
    app.add_option("--log-level", config.log_level, "trace|debug|info|warn|error|critical|off")
        ->capture_default_str();
    app.add_option("--dsoc", options.dsoc,
                   "A dsoc/occlusion culler setting, KEY=VALUE with KEY a field of "
                   "visibility::DSOCConfig (the [dsoc] table; --print-config lists them); "
                   "repeatable, overrides the file's [dsoc] entry")
        ->allow_extra_args(false);
    app.add_option("--stats-json", options.stats_json,
                   "Write the end-of-run figures as JSON to this file");
}

} // namespace

int main(int argc, char** argv) {
    dsoc::server::ServerConfig config;
    ProgramOptions options;
    const char* description = "dsoc-server: authoritative game server with interest management";
    {
        // First pass: only to find --config (and to answer --help and bad flags).
        dsoc::server::ServerConfig scratch;
        CLI::App app{description};
        add_options(app, scratch, options);
        CLI11_PARSE(app, argc, argv);
    }
    if (!options.config_file.empty()) {
        if (const auto problems = dsoc::server::apply_config_file(options.config_file, config);
            !problems.empty()) {
            for (const auto& p : problems) {
                std::fprintf(stderr, "invalid config file: %s\n", p.c_str());
            }
            return 2;
        }
    }
    {
        // Second pass: the flags over the file's settings.
        CLI::App app{description};
        add_options(app, config, options);
        CLI11_PARSE(app, argc, argv);
    }
    std::vector<std::string> flag_problems;
    for (const auto& key_value : options.dsoc) { // over the file's [dsoc] entries
        if (auto why = dsoc::server::set_dsoc_setting_from_flag(config.dsoc, key_value);
            !why.empty()) {
            flag_problems.push_back(std::move(why));
        }
    }
    auto problems = dsoc::server::validate(config);
    problems.insert(problems.begin(), flag_problems.begin(), flag_problems.end());
    if (options.print_config) {
        std::fputs(dsoc::server::format_config_toml(config).c_str(), stdout);
    }
    if (!problems.empty()) {
        for (const auto& p : problems) {
            std::fprintf(stderr, "invalid setting: %s\n", p.c_str());
        }
        return 2;
    }
    if (options.print_config) {
        return 0;
    }

    spdlog::set_default_logger(spdlog::stderr_color_mt("server"));
    spdlog::set_level(spdlog::level::from_str(config.log_level));
    spdlog::set_pattern("[%H:%M:%S.%e] [server] [%^%l%$] %v");

    const auto started = std::chrono::steady_clock::now();
    auto loaded = dsoc::maps::load_map(config.map, dsoc::maps::MapSearch::from_environment());
    if (!loaded) {
        spdlog::error("cannot load map '{}': {}", config.map, loaded.error().message());
        return 2;
    }
    auto map = std::make_shared<const dsoc::maps::Map>(std::move(loaded).value());
    // The map's sanity findings, logged once here (dsoc-mapinfo lists the same).
    const auto findings = dsoc::maps::check_map(*map);
    for (const auto& finding : findings) {
        if (finding.severity == dsoc::maps::FindingSeverity::unusable) {
            spdlog::error("map '{}' is unusable: {}: {}", config.map, finding.code, finding.text);
        } else {
            spdlog::warn("map '{}': {}: {}", config.map, finding.code, finding.text);
        }
    }
    if (dsoc::maps::any_unusable(findings)) {
        return 2;
    }
    spdlog::info(
        "map {} loaded in {:.0f} ms: {} occluders, {} collision brushes, {} spawn points",
        map->name,
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
            .count(),
        map->occluders.size(), map->collision_brushes.size(), map->spawn_points.size());

    boost::asio::io_context io;
    dsoc::server::Server server(io, config, map);
    std::uint16_t port = 0;
    try {
        port = server.start();
    } catch (const std::exception& e) {
        spdlog::error("cannot start on {}:{}: {}", config.bind_address, config.port, e.what());
        return 1;
    }
    // Machine-readable lines for scripts that started us with --port 0.
    std::printf("listening on port %u\n", static_cast<unsigned>(port));

    dsoc::server::MetricsEndpoint metrics(io, [&server] { return server.render_metrics(); });
    if (config.metrics_port >= 0) {
        try {
            const auto metrics_port = metrics.start(
                config.metrics_bind_address, static_cast<std::uint16_t>(config.metrics_port));
            spdlog::info("metrics on http://{}:{}/metrics", config.metrics_bind_address,
                         metrics_port);
            std::printf("metrics on port %u\n", static_cast<unsigned>(metrics_port));
        } catch (const std::exception& e) {
            spdlog::error("cannot serve metrics on {}:{}: {}", config.metrics_bind_address,
                          config.metrics_port, e.what());
            return 1;
        }
    }
    std::fflush(stdout);

    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code& ec, int signal) {
        if (!ec) {
            spdlog::info("signal {} received", signal);
            metrics.stop();
            server.shutdown([&] { signals.cancel(); });
        }
    });
    boost::asio::steady_timer stop_timer(io);
    if (config.duration_s > 0.0) {
        stop_timer.expires_after(
            std::chrono::milliseconds(static_cast<long>(config.duration_s * 1000)));
        stop_timer.async_wait([&](const boost::system::error_code& ec) {
            if (!ec) {
                metrics.stop();
                server.shutdown([&] { signals.cancel(); });
            }
        });
    }

    io.run();

    std::cout << dsoc::server::format_summary(server.stats(), config);
    if (!options.stats_json.empty()) {
        std::ofstream out(options.stats_json);
        out << dsoc::server::format_json(server.stats(), config) << "\n";
        if (!out) {
            spdlog::error("cannot write {}", options.stats_json);
            return 1;
        }
    }
    return 0;
}
