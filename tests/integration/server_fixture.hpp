#pragma once
// Runs a real dsoc server on loopback (port 0) on its own thread.

#include "dsoc/server/server.hpp"
#include "dsoc/simclient/load_config.hpp"
#include "dsoc/simclient/load_run.hpp"
#include "support/test_maps.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <future>
#include <thread>

namespace dsoc::testing {

class RunningServer {
public:
    /// Runs the server as dsoc-server does: on an IoLoop with the config's gather.
    explicit RunningServer(server::ServerConfig config)
        : loop_(io_, std::chrono::microseconds(config.io_gather_us)),
          server_(io_, prepare(std::move(config)), rooms_map()) {
        server_.set_io_loop(&loop_);
        port_ = server_.start();
        thread_ = std::thread([this] { loop_.run(); });
    }
    ~RunningServer() { stop(); }
    RunningServer(const RunningServer&) = delete;
    RunningServer& operator=(const RunningServer&) = delete;

    /// Graceful shutdown; afterwards stats() is safe to read.
    void stop() {
        if (!thread_.joinable()) {
            return;
        }
        boost::asio::post(io_, [this] { server_.shutdown(); });
        thread_.join();
    }

    [[nodiscard]] std::uint16_t port() const { return port_; }
    [[nodiscard]] const server::ServerStats& stats() const { return server_.stats(); }
    /// After stop().
    [[nodiscard]] const server::UdpEndpoint* udp_endpoint() const { return server_.udp_endpoint(); }
    /// After stop().
    [[nodiscard]] std::string render_metrics() const { return server_.render_metrics(); }

private:
    static server::ServerConfig prepare(server::ServerConfig c) {
        c.port = 0;
        c.bind_address = "127.0.0.1";
        // Test servers accept clients without tokens unless the test gives them a key.
        c.insecure = c.token_key_file.empty();
        // No bake in these tests (a minute for oa_dm4, into the user's cache): the dsoc
        // policy runs its exact stages. The baked stage has tests of its own.
        c.baked_stage = false;
        return c;
    }

    boost::asio::io_context io_;
    server::IoLoop loop_; // before the server, which wakes it until it is destroyed
    server::Server server_;
    std::uint16_t port_ = 0;
    std::thread thread_;
};

/// Quiet simulated clients for a test against `server`: `clients` of them, joining over
/// `ramp_up_s`, each leaving after `duration_s`, over TCP (the stream these tests check;
/// UDP's own tests set udp).
inline simclient::LoadConfig load_config(const RunningServer& server, int clients,
                                         double duration_s, double ramp_up_s) {
    simclient::LoadConfig lc;
    lc.transport = simclient::LoadConfig::Transport::tcp;
    lc.port = server.port();
    lc.clients = clients;
    lc.duration_s = duration_s;
    lc.ramp_up_s = ramp_up_s;
    lc.progress = false;
    return lc;
}

/// Runs the simulated clients of `lc` until every one has said goodbye and the server
/// closed it; returns their report.
inline simclient::LoadReport run_load(const simclient::LoadConfig& lc) {
    boost::asio::io_context io;
    simclient::LoadRun run(io, lc);
    run.start();
    io.run();
    return run.report();
}

} // namespace dsoc::testing
