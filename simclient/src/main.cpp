// dsoc-simclient: headless simulated clients; a load generator and protocol checker.

#include "dsoc/cli/program.hpp"
#include "dsoc/simclient/load_run.hpp"

#include <CLI/CLI.hpp>
#include <boost/asio/signal_set.hpp>

#include <csignal>
#include <fstream>
#include <iostream>

int main(int argc, char** argv) {
    dsoc::simclient::LoadConfig config;
    std::string server = "127.0.0.1:27960";
    std::string report_file;
    bool quiet = false;

    CLI::App app{
        "dsoc-simclient: simulated clients that load a dsoc server and check the protocol.\n"
        "Exits 1 when a client failed to connect, saw a protocol error or was dropped."};
    dsoc::cli::set_up(app, "dsoc-simclient");
    app.add_option("--server", server, "Server address HOST:PORT")->capture_default_str();
    app.add_option("--clients", config.clients, "Simulated clients")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    app.add_option("--duration", config.duration_s, "Run time, ramp-up included [s]")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--ramp-up", config.ramp_up_s, "Spread the connects over this time [s]")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    app.add_option("--report", report_file, "Write the JSON report to this file");
    app.add_option("--seed", config.seed, "Seed of the wandering inputs")->capture_default_str();
    app.add_option("--audit-every", config.audit_every_ticks,
                   "Check the decoded replica against the server's exact poses every N ticks "
                   "(0: never)")
        ->capture_default_str();
    app.add_flag("--quiet", quiet, "No progress lines");
    std::string token_key_file;
    std::string token_hex;
    app.add_option("--token-key-file", token_key_file,
                   "Server's token key: each client mints a token for client id base + index");
    app.add_option("--client-id-base", config.client_id_base, "First client id (with a key)")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--token", token_hex,
                   "Connect token (hex, from dsoc-token mint) sent by every client")
        ->excludes("--token-key-file");
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }
    if (!token_key_file.empty()) {
        dsoc::protocol::TokenKey key;
        std::string error;
        if (!dsoc::protocol::load_token_key(token_key_file, key, error)) {
            std::cerr << "--token-key-file: " << error << "\n";
            return 2;
        }
        config.token_key = key;
        // Valid through the whole run: ramp-up, duration and a margin for clock skew.
        config.token_ttl_s = static_cast<std::uint64_t>(config.duration_s) + 60;
    }
    if (!token_hex.empty() && !dsoc::protocol::from_hex(token_hex, config.connect_token)) {
        std::cerr << "--token: expected hex digits\n";
        return 2;
    }

    const auto colon = server.rfind(':');
    if (colon == std::string::npos) {
        std::cerr << "--server: expected HOST:PORT, got '" << server << "'\n";
        return 2;
    }
    config.host = server.substr(0, colon);
    try {
        const int port = std::stoi(server.substr(colon + 1));
        if (port <= 0 || port > 65535) {
            throw std::out_of_range("port");
        }
        config.port = static_cast<std::uint16_t>(port);
    } catch (const std::exception&) {
        std::cerr << "--server: bad port in '" << server << "'\n";
        return 2;
    }
    if (config.host == "localhost") {
        config.host = "127.0.0.1";
    }
    if (config.ramp_up_s > config.duration_s) {
        std::cerr << "--ramp-up must not exceed --duration\n";
        return 2;
    }
    config.progress = !quiet;

    boost::asio::io_context io;
    dsoc::simclient::LoadRun run(io, config);
    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code& ec, int) {
        if (!ec) {
            run.stop();
        }
    });
    run.start();
    // Run until every client has closed; then drop the signal wait so run() returns.
    boost::asio::steady_timer watcher(io);
    std::function<void()> watch = [&] {
        watcher.expires_after(std::chrono::milliseconds(50));
        watcher.async_wait([&](const boost::system::error_code& ec) {
            if (ec) {
                return;
            }
            bool all_done = true;
            for (const auto& c : run.clients()) {
                all_done = all_done && c->finished();
            }
            if (all_done) {
                signals.cancel();
                return;
            }
            watch();
        });
    };
    watch();
    io.run();

    const auto report = run.report();
    std::cout << dsoc::simclient::format_summary(report);
    if (!report_file.empty()) {
        std::ofstream out(report_file);
        out << dsoc::simclient::format_json(report) << "\n";
        if (!out) {
            std::cerr << "cannot write report to " << report_file << "\n";
            return 1;
        }
    }
    return report.passed() ? 0 : 1;
}
