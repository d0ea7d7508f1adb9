// dsoc-simclient: headless simulated clients; a load generator and protocol checker.

#include "dsoc/cli/program.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/simclient/parallel_load_run.hpp"
#include "dsoc/simclient/report_figures.hpp"
#include "dsoc/simclient/scenario_file.hpp"

#include <CLI/CLI.hpp>
#include <boost/asio/signal_set.hpp>

#include <csignal>
#include <fstream>
#include <iostream>

namespace {

constexpr const char* kProgram = "dsoc-simclient";

/// "dsoc-simclient: <what>" on stderr; the usage exit status.
int usage_error(const std::string& what) {
    std::cerr << kProgram << ": " << what << "\n";
    return dsoc::cli::exit_usage;
}

/// Splits HOST:PORT[,HOST:PORT...] into `config` (the first as host and port, the
/// others as more_servers); false with `error` when malformed.
bool parse_server(const std::string& servers, dsoc::simclient::LoadConfig& config,
                  std::string& error) {
    std::vector<std::pair<std::string, std::uint16_t>> parsed;
    std::size_t start = 0;
    while (start <= servers.size()) {
        const std::size_t comma = std::min(servers.find(',', start), servers.size());
        const std::string server = servers.substr(start, comma - start);
        start = comma + 1;
        const auto colon = server.rfind(':');
        if (colon == std::string::npos || colon == 0) {
            error = "--server: expected HOST:PORT, got '" + server + "'";
            return false;
        }
        try {
            const int port = std::stoi(server.substr(colon + 1));
            if (port <= 0 || port > 65535) {
                throw std::out_of_range("port");
            }
            parsed.emplace_back(server.substr(0, colon), static_cast<std::uint16_t>(port));
        } catch (const std::exception&) {
            error = "--server: bad port in '" + server + "'";
            return false;
        }
    }
    config.host = parsed.front().first;
    config.port = parsed.front().second;
    config.more_servers.assign(parsed.begin() + 1, parsed.end());
    return true;
}

void print_figures() {
    for (const auto& f : dsoc::simclient::report_figures()) {
        std::cout << f.name << "  " << f.meaning << "; " << dsoc::simclient::describe(f.dimension)
                  << "\n";
    }
}

} // namespace

int main(int argc, char** argv) {
    dsoc::simclient::LoadConfig config;
    std::string server = "127.0.0.1:27960";
    std::string report_file;
    std::string scenario_file;
    std::string timeseries_file;
    std::vector<std::string> threshold_texts;
    bool quiet = false;
    bool list_figures = false;
    int threads = 1;

    CLI::App app{"dsoc-simclient: simulated clients that load a dsoc server and check the "
                 "protocol.\nExits 0 when the run passed; 1 when it failed (a session failed "
                 "for any reason, a protocol error, an unexpected server shutdown, a threshold "
                 "not met); 2 on a bad command line or scenario file."};
    dsoc::cli::set_up(app, kProgram);
    dsoc::cli::add_setting(app, "--server", server,
                           "Server address HOST:PORT; several, comma-separated, for the "
                           "gateways of one world: clients are spread over them, and one that "
                           "loses its server reconnects to the next (a failover)");
    auto* clients = dsoc::cli::add_setting(app, "--clients", config.clients, "Simulated clients")
                        ->check(CLI::Range(1, 100000));
    auto* duration = dsoc::cli::add_setting(app, "--duration", config.duration_s,
                                            "Run time, ramp-up included [s]")
                         ->check(CLI::PositiveNumber);
    auto* ramp_up = dsoc::cli::add_setting(app, "--ramp-up", config.ramp_up_s,
                                           "Spread the connects over this time [s]")
                        ->check(CLI::NonNegativeNumber);
    app.add_option("--scenario", scenario_file,
                   "Scenario file (TOML): stages, groups of clients, thresholds "
                   "(docs/simclient.md)")
        ->excludes(clients)
        ->excludes(duration)
        ->excludes(ramp_up);
    app.add_option("--threshold", threshold_texts,
                   "Fail the run unless FIGURE OP VALUE holds, e.g. 'interarrival_p99<50ms' "
                   "(repeatable; --list-figures names the figures)")
        ->check([](const std::string& text) {
            dsoc::simclient::Threshold t;
            std::string error;
            return dsoc::simclient::parse_threshold(text, t, error) ? std::string() : error;
        });
    app.add_flag("--list-figures", list_figures,
                 "List the figures a threshold may name, with their units, and exit");
    app.add_option("--report", report_file, "Write the JSON report to this file");
    app.add_option("--timeseries", timeseries_file,
                   "Write one JSON line per second to this file (docs/simclient.md)");
    dsoc::cli::add_setting(app, "--seed", config.seed, "Seed of the wandering inputs");
    dsoc::cli::add_setting(
        app, "--check-every", config.check_every,
        "One client in N decodes and checks each snapshot; the others acknowledge it "
        "unread, as a load generator that discards response bodies (spectators always "
        "decode; 1: all)")
        ->check(CLI::PositiveNumber);
    dsoc::cli::add_setting(
        app, "--audit-every", config.audit_every_ticks,
        "Check the decoded replica against the server's exact poses every N ticks "
        "(0: never)");
    app.add_option("--connect-timeout", config.connect_timeout_s,
                   "Resolve, connect and get the server's hello within this time [s] (default "
                   "5, or the scenario's connect_timeout)")
        ->check(CLI::PositiveNumber);
    dsoc::cli::add_setting(
        app, "--protocol-version", config.protocol_version,
        "Announce this protocol version in the hello (testing aid: a server refuses "
        "any other than its own)");
    const std::map<std::string, dsoc::simclient::LoadConfig::Transport> transports{
        {"tcp", dsoc::simclient::LoadConfig::Transport::tcp},
        {"udp", dsoc::simclient::LoadConfig::Transport::udp}};
    app.add_option("--transport", config.transport,
                   "udp: acknowledged-delta snapshots over UDP datagrams; tcp: compact "
                   "snapshots over a TCP stream (docs/protocol.md)")
        ->transform(CLI::CheckedTransformer(transports, CLI::ignore_case))
        ->default_str("udp");
    dsoc::cli::add_setting(
        app, "--udp-loss", config.udp_faults.loss,
        "UDP only: drop each datagram either way with this probability (emulated "
        "loss)")
        ->check(CLI::Range(0.0, 0.9));
    dsoc::cli::add_setting(app, "--udp-duplicate", config.udp_faults.duplicate,
                           "UDP only: deliver each datagram either way twice with this probability")
        ->check(CLI::Range(0.0, 0.9));
    dsoc::cli::add_setting(
        app, "--udp-reorder", config.udp_faults.reorder,
        "UDP only: hold each datagram either way back behind the next one with this "
        "probability")
        ->check(CLI::Range(0.0, 0.9));
    dsoc::cli::add_setting(
        app, "--threads", threads,
        "Threads, each running its share of the clients (at most one per client; "
        "a load generator on a machine of its own wants one per core)")
        ->check(CLI::Range(1, 1024));
    app.add_flag("--quiet", quiet, "No progress lines");
    std::string token_key_file;
    std::string token_hex;
    app.add_option("--token-key-file", token_key_file,
                   "Server's token key: each client mints a token for client id base + index");
    dsoc::cli::add_setting(app, "--client-id-base", config.client_id_base,
                           "First client id (with a key)")
        ->check(CLI::PositiveNumber);
    app.add_option("--token", token_hex,
                   "Connect token (hex, from dsoc-token mint) sent by every client")
        ->excludes("--token-key-file");
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }
    if (list_figures) {
        print_figures();
        return dsoc::cli::exit_ok;
    }
    for (const auto& text : threshold_texts) {
        dsoc::simclient::Threshold t;
        std::string error;
        (void)dsoc::simclient::parse_threshold(text, t, error); // checked by CLI11 above
        config.thresholds.push_back(std::move(t));
    }
    if (!scenario_file.empty()) {
        dsoc::simclient::Scenario scenario;
        std::string error;
        if (!dsoc::simclient::load_scenario_file(scenario_file, scenario, error)) {
            return usage_error("--scenario: " + error);
        }
        config.scenario = std::move(scenario);
    } else if (config.ramp_up_s > config.duration_s) {
        return usage_error("--ramp-up must not exceed --duration");
    }
    const double run_s = config.scenario ? config.scenario->length_s() : config.duration_s;
    if (!token_key_file.empty()) {
        dsoc::protocol::TokenKey key;
        std::string error;
        if (!dsoc::protocol::load_token_key(token_key_file, key, error)) {
            return usage_error("--token-key-file: " + error);
        }
        config.token_key = key;
        // Valid through the whole run and a margin for clock skew.
        config.token_ttl_s = static_cast<std::uint64_t>(run_s) + 60;
    }
    if (!token_hex.empty() && !dsoc::protocol::from_hex(token_hex, config.connect_token)) {
        return usage_error("--token: expected hex digits");
    }
    if (std::string error; !parse_server(server, config, error)) {
        return usage_error(error);
    }
    if (config.host == "localhost") {
        config.host = "127.0.0.1";
    }
    for (auto& [host, port] : config.more_servers) {
        if (host == "localhost") {
            host = "127.0.0.1";
        }
    }
    config.progress = !quiet;

    std::ofstream timeseries;
    if (!timeseries_file.empty()) {
        timeseries.open(timeseries_file);
        if (!timeseries) {
            std::cerr << kProgram << ": cannot write the time series to " << timeseries_file
                      << "\n";
            return dsoc::cli::exit_failure;
        }
    }

    boost::asio::io_context io;
    dsoc::simclient::ParallelLoadRun run(io, config, threads);
    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code& ec, int number) {
        if (!ec) {
            run.stop(number == SIGINT ? "interrupted (SIGINT)" : "terminated (SIGTERM)");
        }
    });
    if (timeseries.is_open()) {
        run.on_second([&](const dsoc::simclient::SecondSample& sample) {
            timeseries << dsoc::simclient::format_timeseries_line(sample) << "\n" << std::flush;
        });
    }
    // Once every session has closed, drop the signal wait so that run() returns.
    run.on_finished([&] { signals.cancel(); });
    run.start();
    io.run();

    const auto report = run.report();
    std::cout << dsoc::simclient::format_summary(report);
    if (!report_file.empty()) {
        std::ofstream out(report_file);
        out << dsoc::simclient::format_json(report) << "\n";
        if (!out) {
            std::cerr << kProgram << ": cannot write report to " << report_file << "\n";
            return dsoc::cli::exit_failure;
        }
    }
    if (timeseries.is_open() && !timeseries) {
        std::cerr << kProgram << ": cannot write the time series to " << timeseries_file << "\n";
        return dsoc::cli::exit_failure;
    }
    return report.passed() ? dsoc::cli::exit_ok : dsoc::cli::exit_failure;
}
