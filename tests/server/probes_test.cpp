// /healthz and /readyz of a real server on loopback: not ready before start() and
// until its first tick, ready while the tick loop runs, not ready once shutdown()
// began; alive throughout.

#include "dsoc/server/metrics_endpoint.hpp"
#include "dsoc/server/server.hpp"
#include "support/http_client.hpp"
#include "support/io_thread.hpp"
#include "support/test_maps.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace dsoc::server {
namespace {

using dsoc::testing::http_body;
using dsoc::testing::http_get;
using dsoc::testing::http_status;
using dsoc::testing::run_on_io_thread;

TEST(Readiness, FollowsTheServersLife) {
    boost::asio::io_context io;
    ServerConfig config;
    config.port = 0;
    config.insecure = true;
    config.baked_stage = false; // no bake in tests
    config.bots = 4;
    config.tick_rate = 20;
    Server server(io, config, dsoc::testing::rooms_map());
    MetricsEndpoint endpoint(
        io, [&] { return server.render_metrics(); }, [&] { return server.readiness(); });
    const std::uint16_t port = endpoint.start("127.0.0.1", 0);
    std::thread io_thread([&] { io.run(); }); // the endpoint's accept keeps it running

    const auto before_start = http_get(port, "/readyz");
    const auto alive_before_start = http_get(port, "/healthz");
    run_on_io_thread(io, [&] { server.start(); });
    std::string ready;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    do {
        ready = http_get(port, "/readyz");
    } while (http_status(ready) != 200 && std::chrono::steady_clock::now() < deadline);
    std::uint64_t ticks_when_ready = 0;
    run_on_io_thread(io, [&] { ticks_when_ready = server.stats().ticks; });
    run_on_io_thread(io, [&] { server.shutdown(); });
    const auto shutting_down = http_get(port, "/readyz");
    const auto alive_after = http_get(port, "/healthz");
    boost::asio::post(io, [&] { endpoint.stop(); });
    io_thread.join();

    EXPECT_EQ(http_status(before_start), 503) << before_start;
    EXPECT_EQ(http_body(before_start), "not ready: not started\n");
    EXPECT_EQ(http_status(alive_before_start), 200) << alive_before_start;
    EXPECT_EQ(http_status(ready), 200) << ready;
    EXPECT_GE(ticks_when_ready, 1u); // ready means a tick has run
    EXPECT_EQ(http_status(shutting_down), 503) << shutting_down;
    EXPECT_EQ(http_body(shutting_down), "not ready: shutting down\n");
    EXPECT_EQ(http_status(alive_after), 200) << alive_after;
}

TEST(Readiness, WaitsForTheFirstTick) {
    boost::asio::io_context io;
    ServerConfig config;
    config.port = 0;
    config.insecure = true;
    config.baked_stage = false;
    config.bots = 0;
    config.tick_rate = 1; // the first tick is due a second after start()
    Server server(io, config, dsoc::testing::rooms_map());
    server.start();
    // No tick can have run: the io_context has not run at all.
    const Readiness started = server.readiness();
    EXPECT_FALSE(started.ready);
    EXPECT_EQ(started.why, "waiting for the first tick");
    server.shutdown();
    io.run();
    EXPECT_EQ(server.readiness().why, "shutting down");
}

} // namespace
} // namespace dsoc::server
