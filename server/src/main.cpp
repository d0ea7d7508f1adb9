// dsoc-server: the game server with occlusion-aware interest management.
//
// Start-up, in order: the settings (the config file from --config or $DSOC_CONFIG, the
// flags over it) and their checks; the token key; the log; the /metrics, /healthz and
// /readyz endpoint, which answers from then on (/readyz: 503 until the first tick);
// the map and its baked table (a minute the first time); the game port and the tick
// loop. Exit statuses as every dsoc program's (dsoc/cli/program.hpp): 0 after a
// clean stop, 1 when serving failed, 2 when the settings, the key or the map are wrong.

#include "dsoc/cli/build_info.hpp"
#include "dsoc/cli/program.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/maps/map_checks.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/server/config_file.hpp"
#include "dsoc/server/dsoc_settings.hpp"
#include "dsoc/server/io_loop.hpp"
#include "dsoc/server/logging.hpp"
#include "dsoc/server/metrics_endpoint.hpp"
#include "dsoc/server/process_metrics.hpp"
#include "dsoc/server/server.hpp"
#include "dsoc/server/startup_stop.hpp"
#include "dsoc/server/stats_report.hpp"
#include "dsoc/server/thread_metrics.hpp"
#include "dsoc/server/world_role.hpp"

#include "program_options.hpp"

#include <CLI/CLI.hpp>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/signal_set.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

using dsoc::cli::exit_failure;
using dsoc::cli::exit_ok;
using dsoc::cli::exit_usage;
using dsoc::server::ServerConfig;

/// The environment variable naming the config file when --config is not given.
constexpr const char* kConfigEnvironment = "DSOC_CONFIG";

struct ProgramOptions {
    std::string config_file;
    std::string stats_json;
    bool print_config = false;
    bool check_config = false;
    std::vector<std::string> dsoc; ///< --dsoc KEY=VALUE, in order
};

/// Every flag, bound to `config` and `options`. Flags given on the command line
/// overwrite what the config file set.
void add_options(CLI::App& app, ServerConfig& config, ProgramOptions& options) {
    app.add_option("--config", options.config_file,
                   "TOML file with settings (keys as in --print-config); flags override it. "
                   "Default: $DSOC_CONFIG when set");
    app.add_flag("--print-config", options.print_config,
                 "Print the effective settings as TOML and exit 0; what keeps them from "
                 "starting the server is listed in comments at the top and on stderr");
    app.add_flag("--check-config", options.check_config,
                 "Check the settings, the token key file and the map as a start would, "
                 "without serving; exit 0 when the server would start, 2 (naming every "
                 "problem) when not");
    dsoc::cli::add_setting(app, "--role", config.role,
                           "single (the whole game), world (the world of a scaled-out game, "
                           "published on NATS) or gateway (clients and their interest, the "
                           "world from NATS); docs/scale-out.md");
    dsoc::cli::add_setting(app, "--nats-url", config.nats_url,
                           "NATS server(s) of a world and its gateways (nats://host:port)");
    dsoc::cli::add_setting(app, "--world-name", config.world_name,
                           "The world's name: its NATS subjects are dsoc.<name>.*");
    dsoc::cli::add_setting(app, "--bind", config.bind_address, "Address to listen on");
    dsoc::cli::add_setting(app, "--port", config.port,
                           "TCP port (and UDP's, with --udp true); 0 picks a free one");
    dsoc::server::add_world_options(app, config);
    dsoc::server::add_policy_options(app, config);
    dsoc::cli::add_setting(app, "--tbv-strategy", config.tbv_strategy,
                           "dsoc TBVs, when on ([dsoc] tbvs_enabled = true; off by default): "
                           "adaptive | explicit | fuzzy");
    dsoc::cli::add_choice_option(app, "--culler", config.culler,
                                 "Occlusion culler stages: shaft | pyramid | both");
    dsoc::cli::add_setting(
        app, "--culling-budget", config.culling_budget,
        "Share of the tick period for culling; clients after it get the cheapest "
        "conservative answer (0 = off)");
    dsoc::cli::add_setting(app, "--pvs-stage", config.pvs_stage,
                           "Reject with the map's PVS before the culler (true/false)");
    dsoc::cli::add_setting(app, "--region-margin", config.region_reuse_margin,
                           "dsoc: reuse a client's culler region within this margin [units]");
    dsoc::cli::add_setting(app, "--latency-allowance-ms", config.latency_allowance_ms,
                           "Client movement the server covers: RTT + interpolation delay [ms]");
    app.add_option("--trace", config.trace_file, "Write a replication trace (JSON Lines) here");
    dsoc::cli::add_setting(app, "--trace-every", config.trace_every,
                           "Record every k-th tick in the trace");
    dsoc::cli::add_setting(app, "--distance-radius", config.distance_radius,
                           "Radius of the distance policy [units]");
    dsoc::cli::add_setting(
        app, "--threads", config.threads,
        "Worker threads for the per-client tick work, beside the I/O thread; 0: one "
        "per core");
    dsoc::cli::add_setting(app, "--position-quantum-near", config.position_quantum_near,
                           "Snapshot position precision, entities updated every tick [units]");
    dsoc::cli::add_setting(app, "--position-quantum-mid", config.position_quantum_mid,
                           "Snapshot position precision, entities updated every 2nd tick [units]");
    dsoc::cli::add_setting(app, "--position-quantum-far", config.position_quantum_far,
                           "Snapshot position precision, entities updated every 4th tick [units]");
    dsoc::cli::add_setting(app, "--angle-steps", config.angle_steps,
                           "Snapshot angle steps per full turn");
    dsoc::cli::add_setting(
        app, "--heard-quantum", config.heard_quantum,
        "Position precision of entities a client hears but does not see [units]");
    dsoc::cli::add_setting(
        app, "--network-lod", config.network_lod,
        "Coarser, rarer updates for distant entities (dsoc/occlusion) (true/false)");
    dsoc::cli::add_setting(app, "--max-clients", config.max_clients, "Connected clients at most");
    dsoc::cli::add_setting(app, "--max-pending-connections", config.max_pending_connections,
                           "TCP connections waiting for their hello at most, in all (beyond: "
                           "the oldest of the address holding the most is closed)");
    dsoc::cli::add_setting(app, "--max-pending-per-source", config.max_pending_per_source,
                           "TCP connections waiting for their hello from one address (an IPv6 "
                           "/64) before its new ones get 500 ms to say it");
    dsoc::cli::add_setting(app, "--max-frame-bytes", config.max_frame_bytes,
                           "Largest frame a client may send [bytes]");
    dsoc::cli::add_setting(app, "--max-send-queue-bytes", config.max_send_queue_bytes,
                           "Unsent bytes per client before it is dropped as too slow");
    dsoc::cli::add_setting(app, "--handshake-timeout-ms", config.handshake_timeout_ms,
                           "Close connections that send no hello within this time [ms]");
    dsoc::cli::add_setting(app, "--udp", config.udp,
                           "Also serve clients over UDP on the same port number (true/false)");
    dsoc::cli::add_setting(app, "--udp-timeout-ms", config.udp_timeout_ms,
                           "Disconnect a UDP client from which nothing arrived this long [ms]");
    dsoc::cli::add_setting(app, "--udp-handshake-rate", config.udp_handshake_rate,
                           "UDP responses with a valid cookie one source address may send per "
                           "second [1/s]");
    dsoc::cli::add_setting(app, "--udp-challenge-rate", config.udp_challenge_rate,
                           "UDP requests the server answers with a challenge per second, all "
                           "sources together [1/s]");
    dsoc::cli::add_setting(app, "--heap-metrics", config.heap_metrics,
                           "/metrics also reads glibc malloc's live and free bytes (a "
                           "diagnosis: each scrape stalls allocation; jemalloc's are always "
                           "read; true/false)");
    dsoc::cli::add_setting(app, "--max-speed", config.max_speed,
                           "Speed bound of every entity [units/s]");
    dsoc::cli::add_setting(app, "--duration", config.duration_s,
                           "Stop after this many seconds (0: run until signalled)");
    dsoc::cli::add_setting(app, "--slow-client-timeout-ms", config.slow_client_timeout_ms,
                           "Disconnect a client whose snapshot stays unsent this long [ms]");
    dsoc::cli::add_setting(app, "--socket-send-buffer-bytes", config.socket_send_buffer_bytes,
                           "SO_SNDBUF of client sockets; 0 keeps the OS default [bytes]");
    dsoc::cli::add_setting(app, "--io-gather-us", config.io_gather_us,
                           "After each wakeup the I/O thread lets socket events gather this long, "
                           "reading many clients' inputs in one wakeup; timers and pings may be "
                           "late by as much (0: wake for each) [us]");
    dsoc::cli::add_setting(app, "--max-inputs-per-second", config.max_inputs_per_second,
                           "Messages a client may send per second; more are dropped, twice that "
                           "disconnects");
    app.add_flag("--insecure", config.insecure,
                 "Accept clients without connect tokens (local tests and demos only)");
    app.add_option("--token-key-file", config.token_key_file,
                   "Connect-token key file (64 hex digits; dsoc-token keygen makes one)");
    dsoc::cli::add_setting(app, "--metrics-port", config.metrics_port,
                           "Serve Prometheus /metrics on this port (-1 off, 0 any free port)");
    dsoc::cli::add_setting(app, "--metrics-bind", config.metrics_bind_address,
                           "Address of the metrics endpoint");
    dsoc::cli::add_setting(app, "--log-level", config.log_level,
                           "trace|debug|info|warn|error|critical|off");
    dsoc::cli::add_setting(app, "--log-format", config.log_format,
                           "Log on stderr as text, or as json (one object a line: time, level, "
                           "logger, msg)");
    app.add_option("--dsoc", options.dsoc,
                   "A dsoc/occlusion culler setting, KEY=VALUE with KEY a field of "
                   "visibility::DSOCConfig (the [dsoc] table; --print-config lists them); "
                   "repeatable, overrides the file's [dsoc] entry")
        ->allow_extra_args(false);
    app.add_option("--stats-json", options.stats_json,
                   "Write the end-of-run figures as JSON to this file");
}

/// The settings: the config file (--config, else $DSOC_CONFIG), then the flags over
/// it. Returns the exit status when the program must stop here: --help or --version,
/// or a command line or file that cannot be read. Values of --dsoc flags that cannot
/// be used are added to `flag_problems`.
std::optional<int> read_settings(int argc, char** argv, ServerConfig& config,
                                 ProgramOptions& options, std::vector<std::string>& flag_problems) {
    const auto parse_flags = [&](ServerConfig& into) {
        CLI::App app{"dsoc-server: authoritative game server with interest management"};
        dsoc::cli::set_up(app, "dsoc-server");
        add_options(app, into, options);
        return dsoc::cli::parse(app, argc, argv);
    };
    // First pass: only to find --config (and to answer --help, --version, bad flags).
    if (ServerConfig scratch; const auto stop = parse_flags(scratch)) {
        return stop;
    }
    std::string origin;
    if (options.config_file.empty()) {
        if (const char* path = std::getenv(kConfigEnvironment); path != nullptr && *path != '\0') {
            options.config_file = path;
            origin = std::string(" (from ") + kConfigEnvironment + ")";
        }
    }
    if (!options.config_file.empty()) {
        if (const auto problems = dsoc::server::apply_config_file(options.config_file, config);
            !problems.empty()) {
            for (const auto& p : problems) {
                std::fprintf(stderr, "invalid config file%s: %s\n", origin.c_str(), p.c_str());
            }
            return exit_usage;
        }
    }
    // Second pass: the flags over the file's settings.
    if (const auto stop = parse_flags(config)) {
        return stop;
    }
    for (const auto& key_value : options.dsoc) { // over the file's [dsoc] entries
        if (auto why = dsoc::server::set_dsoc_setting_from_flag(config.dsoc, key_value);
            !why.empty()) {
            flag_problems.push_back(std::move(why));
        }
    }
    return std::nullopt;
}

/// Whether the token key file can be read (Server::start() reads it again): a problem
/// naming the file and why, or empty.
std::string token_key_problem(const ServerConfig& config) {
    if (config.insecure || config.role == "world" || config.token_key_file.empty()) {
        return {}; // no clients; or validate() names a missing key file
    }
    dsoc::protocol::TokenKey key;
    std::string error;
    if (!dsoc::protocol::load_token_key(config.token_key_file, key, error)) {
        return "token_key_file: " + error;
    }
    return {};
}

/// config.map loaded and checked as the server does at start.
struct CheckedMap {
    std::shared_ptr<const dsoc::maps::Map> map; ///< null when it did not load
    std::string load_problem;                   ///< why it did not load
    std::vector<dsoc::maps::MapFinding> findings;
    double load_ms = 0.0;

    [[nodiscard]] bool usable() const {
        return map != nullptr && !dsoc::maps::any_unusable(findings);
    }
};

CheckedMap load_checked_map(const ServerConfig& config) {
    CheckedMap checked;
    const auto started = std::chrono::steady_clock::now();
    auto loaded = dsoc::maps::load_map(config.map, dsoc::maps::MapSearch::from_environment());
    checked.load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
            .count();
    if (!loaded) {
        checked.load_problem =
            dsoc::cli::map_load_failure("--map", config.map, loaded.error().message());
        return checked;
    }
    checked.map = std::make_shared<const dsoc::maps::Map>(std::move(loaded).value());
    // The map's sanity findings (dsoc-mapinfo lists the same).
    checked.findings = dsoc::maps::check_map(*checked.map);
    return checked;
}

/// "map 'X' is unusable: code: text" or "map 'X': code: text".
std::string finding_text(const ServerConfig& config, const dsoc::maps::MapFinding& finding) {
    const bool unusable = finding.severity == dsoc::maps::FindingSeverity::unusable;
    return "map '" + config.map + "'" + (unusable ? " is unusable: " : ": ") + finding.code + ": " +
           finding.text;
}

/// --check-config: everything a start checks, without serving.
int check_config(const ServerConfig& config, std::vector<std::string> problems) {
    if (auto key = token_key_problem(config); !key.empty()) {
        problems.push_back(std::move(key));
    }
    const CheckedMap checked = load_checked_map(config);
    if (!checked.load_problem.empty()) {
        problems.push_back("map: " + checked.load_problem);
    }
    for (const auto& finding : checked.findings) {
        if (finding.severity == dsoc::maps::FindingSeverity::unusable) {
            problems.push_back(finding_text(config, finding));
        } else {
            std::printf("warning: %s\n", finding_text(config, finding).c_str());
        }
    }
    for (const auto& p : problems) {
        std::fprintf(stderr, "invalid setting: %s\n", p.c_str());
    }
    if (!problems.empty()) {
        return exit_usage;
    }
    std::printf("dsoc-server: the settings are good: map %s (%zu occluders), policy %s, port %u\n",
                checked.map->name.c_str(), checked.map->occluders.size(),
                std::string(dsoc::interest::name_of(config.policy)).c_str(),
                static_cast<unsigned>(config.port));
    return exit_ok;
}

/// Runs the io_context on a thread of its own while the caller is busy (loading the
/// map, baking its table), so that /healthz and /readyz answer meanwhile. On
/// destruction it stops that thread and hands the io_context back, with its pending
/// work, to run on the caller's thread: one I/O thread at a time, as the server needs.
class IoDuringStartup {
public:
    IoDuringStartup(boost::asio::io_context& io, bool needed) : io_(io) {
        if (needed) {
            work_.emplace(io.get_executor());
            thread_ = std::thread([&io] {
                dsoc::server::mark_io_thread();
                io.run();
            });
        }
    }
    ~IoDuringStartup() {
        if (thread_.joinable()) {
            work_.reset();
            io_.stop();
            thread_.join();
            io_.restart();
        }
    }
    IoDuringStartup(const IoDuringStartup&) = delete;
    IoDuringStartup& operator=(const IoDuringStartup&) = delete;

private:
    boost::asio::io_context& io_;
    std::optional<boost::asio::executor_work_guard<boost::asio::io_context::executor_type>> work_;
    std::thread thread_;
};

/// Role world: the world process's tick loop on this thread, /metrics and the signals
/// on `io`'s, until a signal or config.duration_s.
int serve_world(const ServerConfig& config, const std::shared_ptr<const dsoc::maps::Map>& map,
                boost::asio::io_context& io, dsoc::server::MetricsEndpoint& metrics,
                std::atomic<dsoc::server::WorldRole*>& live) {
    std::unique_ptr<dsoc::server::WorldRole> world;
    try {
        world = std::make_unique<dsoc::server::WorldRole>(config, map);
    } catch (const dsoc::scaleout::NatsError& e) {
        spdlog::error("cannot reach NATS for world '{}': {}", config.world_name, e.what());
        return exit_failure;
    }
    live.store(world.get());
    std::atomic<bool> stop{false};
    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code& ec, int signal) {
        if (!ec) {
            spdlog::info("signal {} received", signal);
            stop.store(true);
        }
    });
    if (dsoc::server::startup_stop_requested()) { // came while starting, before the set
        spdlog::info("signal received while starting");
        stop.store(true);
    }
    std::thread io_thread([&io] {
        dsoc::server::mark_io_thread();
        io.run();
    });
    std::printf("world %s publishing on %s\n", config.world_name.c_str(),
                dsoc::scaleout::world_subject(config.world_name, "tick").c_str());
    std::fflush(stdout);
    world->run(stop);
    live.store(nullptr);
    signals.cancel();
    metrics.stop();
    io.stop();
    io_thread.join();
    const auto s = world->stats();
    std::printf("world %s: %llu ticks (%llu not published), %llu players joined, %llu left, "
                "%llu inputs, %llu bad messages, %llu gateways lost (%llu back)\n",
                config.world_name.c_str(), static_cast<unsigned long long>(s.ticks),
                static_cast<unsigned long long>(s.ticks_not_published),
                static_cast<unsigned long long>(s.joins), static_cast<unsigned long long>(s.leaves),
                static_cast<unsigned long long>(s.inputs),
                static_cast<unsigned long long>(s.bad_messages),
                static_cast<unsigned long long>(s.gateways_lost),
                static_cast<unsigned long long>(s.gateways_back));
    return exit_ok;
}

/// The server, from the metrics endpoint to the end-of-run summary.
int serve(const ServerConfig& config, const ProgramOptions& options) {
    dsoc::server::set_up_logging(config);
    spdlog::info("{}", dsoc::cli::version_line("dsoc-server"));
    // Until the serving loop's signal_set: a first bake stops and keeps its work.
    dsoc::server::catch_startup_signals();

    boost::asio::io_context io;
    dsoc::server::Server* live = nullptr; // the server, once it runs on this thread
    std::atomic<dsoc::server::WorldRole*> world_live{nullptr}; // role world, once it runs
    const auto& build = dsoc::cli::build_info();
    dsoc::server::MetricsEndpoint metrics(
        io,
        [&] {
            dsoc::server::WorldRole* world = world_live.load();
            std::string text = live != nullptr    ? live->render_metrics()
                               : world != nullptr ? world->render_metrics()
                                                  : std::string();
            dsoc::server::PrometheusText process;
            dsoc::server::write_build_info(process, build.version, build.commit);
            dsoc::server::write_process_metrics(
                process, dsoc::server::read_process_sample(config.heap_metrics));
            dsoc::server::write_thread_metrics(process, dsoc::server::read_thread_roles());
            return text + process.text();
        },
        [&] {
            if (dsoc::server::WorldRole* world = world_live.load(); world != nullptr) {
                return world->stats().ticks > 0
                           ? dsoc::server::Readiness{true, {}}
                           : dsoc::server::Readiness{false, "waiting for the first tick"};
            }
            return live != nullptr
                       ? live->readiness()
                       : dsoc::server::Readiness{false, "loading map '" + config.map + "'"};
        });
    if (config.metrics_port >= 0) {
        try {
            const auto metrics_port = metrics.start(
                config.metrics_bind_address, static_cast<std::uint16_t>(config.metrics_port));
            spdlog::info("metrics on http://{}:{}/metrics (and /healthz, /readyz)",
                         config.metrics_bind_address, metrics_port);
            std::printf("metrics on port %u\n", static_cast<unsigned>(metrics_port));
            std::fflush(stdout);
        } catch (const std::exception& e) {
            spdlog::error("cannot serve metrics on {}:{}: {}", config.metrics_bind_address,
                          config.metrics_port, e.what());
            return exit_failure;
        }
    }

    // Before the server, which wakes it from its workers until it is destroyed.
    dsoc::server::IoLoop io_loop(io, std::chrono::microseconds(config.io_gather_us));
    std::unique_ptr<dsoc::server::Server> server;
    std::shared_ptr<const dsoc::maps::Map> world_map; // role world: the map it runs on
    {
        const IoDuringStartup probes(io, config.metrics_port >= 0);
        const CheckedMap checked = load_checked_map(config);
        if (!checked.load_problem.empty()) {
            spdlog::error("{}", checked.load_problem);
            return exit_usage;
        }
        for (const auto& finding : checked.findings) {
            if (finding.severity == dsoc::maps::FindingSeverity::unusable) {
                spdlog::error("{}", finding_text(config, finding));
            } else {
                spdlog::warn("{}", finding_text(config, finding));
            }
        }
        if (!checked.usable()) {
            return exit_usage;
        }
        spdlog::info(
            "map {} loaded in {:.0f} ms: {} occluders, {} collision brushes, {} spawn points",
            checked.map->name, checked.load_ms, checked.map->occluders.size(),
            checked.map->collision_brushes.size(), checked.map->spawn_points.size());
        if (config.role == "world") {
            world_map = checked.map; // no policy, no table: the gateways hold those
        } else {
            // Builds the policy: loads the map's baked table from the cache, or bakes it.
            try {
                server = std::make_unique<dsoc::server::Server>(io, config, checked.map);
            } catch (const std::exception& e) {
                spdlog::error("{}", e.what());
                return exit_failure;
            }
        }
    }
    if (dsoc::server::startup_stop_requested()) {
        spdlog::info("stopped while starting");
        return exit_failure;
    }
    if (world_map) {
        return serve_world(config, world_map, io, metrics, world_live);
    }
    live = server.get();
    server->set_io_loop(&io_loop);
    std::uint16_t port = 0;
    try {
        port = server->start();
    } catch (const dsoc::scaleout::NatsError& e) {
        spdlog::error("cannot reach NATS for world '{}': {}", config.world_name, e.what());
        return exit_failure;
    } catch (const std::exception& e) {
        spdlog::error("cannot start on {}:{}: {}", config.bind_address, config.port, e.what());
        return exit_failure;
    }
    // Machine-readable line for scripts that started us with --port 0.
    std::printf("listening on port %u\n", static_cast<unsigned>(port));
    std::fflush(stdout);

    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    boost::asio::steady_timer stop_timer(io);
    // /readyz says 503 from here on; the endpoint closes once the clients are gone.
    const auto stop = [&] {
        server->shutdown([&] {
            metrics.stop();
            signals.cancel();
            stop_timer.cancel();
        });
    };
    signals.async_wait([&](const boost::system::error_code& ec, int signal) {
        if (!ec) {
            spdlog::info("signal {} received", signal);
            stop();
        }
    });
    if (dsoc::server::startup_stop_requested()) { // came after the bake, before the set
        spdlog::info("signal received while starting");
        stop();
    }
    if (config.duration_s > 0.0) {
        stop_timer.expires_after(
            std::chrono::milliseconds(static_cast<long>(config.duration_s * 1000)));
        stop_timer.async_wait([&](const boost::system::error_code& ec) {
            if (!ec) {
                stop();
            }
        });
    }

    dsoc::server::mark_io_thread();
    io_loop.run();

    std::cout << dsoc::server::format_summary(server->stats(), config);
    if (!options.stats_json.empty()) {
        std::ofstream out(options.stats_json);
        out << dsoc::server::format_json(server->stats(), config) << "\n";
        if (!out) {
            spdlog::error("cannot write {}", options.stats_json);
            return exit_failure;
        }
    }
    return exit_ok;
}

} // namespace

int main(int argc, char** argv) {
    ServerConfig config;
    ProgramOptions options;
    std::vector<std::string> problems; // every one is listed, each naming the field and why
    if (const auto stop = read_settings(argc, argv, config, options, problems)) {
        return *stop;
    }
    const bool bad_flags = !problems.empty();
    for (auto& p : dsoc::server::validate(config)) {
        problems.push_back(std::move(p));
    }
    if (options.print_config && !bad_flags) {
        // Printed whatever validate() says: the first step of writing a config file.
        std::fputs(dsoc::server::format_config_toml(config, problems).c_str(), stdout);
        for (const auto& p : problems) {
            std::fprintf(stderr,
                         "dsoc-server: to fix before the server starts with these "
                         "settings: %s\n",
                         p.c_str());
        }
        return exit_ok;
    }
    if (options.check_config) {
        return check_config(config, std::move(problems));
    }
    if (problems.empty()) {
        if (auto key = token_key_problem(config); !key.empty()) {
            problems.push_back(std::move(key)); // now, not after a minute of baking
        }
    }
    if (!problems.empty()) {
        for (const auto& p : problems) {
            std::fprintf(stderr, "invalid setting: %s\n", p.c_str());
        }
        return exit_usage;
    }
    return serve(config, options);
}
