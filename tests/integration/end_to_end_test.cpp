// A real server and eight simulated clients over loopback TCP for about two seconds.

#include "server_fixture.hpp"

#include "dsoc/simclient/load_run.hpp"
#include "dsoc/simclient/parallel_load_run.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <set>

namespace dsoc {
namespace {

TEST(EndToEnd, EightClientsGetHelloSnapshotsAndTheirOwnEntity) {
    server::ServerConfig sc;
    sc.bots = 60;
    sc.tick_rate = 30;
    sc.policy = interest::PolicyKind::distance;
    testing::RunningServer server(sc);

    const simclient::LoadConfig lc = testing::load_config(server, 8, 2.0, 0.2);
    boost::asio::io_context io;
    simclient::LoadRun run(io, lc);
    run.start();
    io.run(); // returns once every client has said goodbye and the server closed it
    server.stop();

    const auto report = run.report();
    EXPECT_EQ(report.connected, 8);
    EXPECT_EQ(report.connect_failures, 0);
    EXPECT_EQ(report.protocol_errors, 0u) << simclient::format_summary(report);
    EXPECT_EQ(report.unexpected_disconnects, 0);
    EXPECT_EQ(report.missing_own_entity, 0);
    EXPECT_TRUE(report.passed());
    for (const auto& client : run.clients()) {
        const auto& s = client->stats();
        EXPECT_TRUE(s.hello_received);
        EXPECT_TRUE(s.saw_own_entity);
        // ~1.8 s active at 30 Hz: at least 40 snapshots even on a loaded machine.
        EXPECT_GE(s.snapshots, 40u);
    }
    EXPECT_GT(report.entities_known.mean, 1.0); // more than just themselves

    // Both ends counted every byte of every frame.
    const auto& stats = server.stats();
    EXPECT_EQ(stats.bytes_sent, report.bytes_down);
    EXPECT_EQ(stats.bytes_received, report.bytes_up);
    EXPECT_EQ(stats.snapshots_sent, report.snapshots);
    EXPECT_EQ(stats.disconnects.at("client_quit"), 8u);
}

TEST(EndToEnd, ShutdownTellsEveryClientWhy) {
    server::ServerConfig sc;
    sc.bots = 10;
    testing::RunningServer server(sc);

    // 30 s, far longer than we wait: the server ends it
    const simclient::LoadConfig lc = testing::load_config(server, 4, 30.0, 0.0);
    boost::asio::io_context io;
    simclient::LoadRun run(io, lc);
    run.start();
    std::thread client_thread([&] { io.run(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    server.stop();
    boost::asio::post(io, [&] { run.stop(); });
    client_thread.join();

    const auto report = run.report();
    EXPECT_EQ(report.connected, 4);
    EXPECT_EQ(report.unexpected_disconnects, 0);
    EXPECT_EQ(report.disconnect_reasons.at("server_shutdown"), 4u);
    EXPECT_EQ(server.stats().disconnects.at("server_shutdown"), 4u);
}

TEST(EndToEnd, ClientsPastTheCullingBudgetGetTheCheapestAnswerAndAreCounted) {
    // A budget no tick can meet: every client's culling starts after it, so every
    // client-tick gets the dsoc policy's prepared stage alone (the map's PVS), and the
    // server still runs on time and sends every client its snapshots.
    server::ServerConfig sc;
    sc.bots = 60;
    sc.tick_rate = 30;
    sc.policy = interest::PolicyKind::dsoc;
    sc.culling_budget = 1e-9;
    testing::RunningServer server(sc);

    const auto report = testing::run_load(testing::load_config(server, 4, 1.5, 0.1));
    server.stop();

    EXPECT_EQ(report.connected, 4);
    EXPECT_EQ(report.protocol_errors, 0u) << simclient::format_summary(report);
    EXPECT_TRUE(report.passed());
    EXPECT_EQ(report.missing_own_entity, 0);
    const auto& stats = server.stats();
    EXPECT_GT(stats.cheapest_client_ticks, 4u * 20u); // ~1.4 s at 30 Hz, 4 clients
    EXPECT_LE(stats.cheapest_client_ticks, 4u * stats.ticks);
    std::printf("%llu of at most %llu client-ticks served the cheapest answer\n",
                static_cast<unsigned long long>(stats.cheapest_client_ticks),
                static_cast<unsigned long long>(4u * stats.ticks));
}

TEST(EndToEnd, ThreeThreadsOfClientsAreOneRunWithOneReport) {
    server::ServerConfig sc;
    sc.bots = 30;
    sc.tick_rate = 30;
    sc.policy = interest::PolicyKind::distance;
    testing::RunningServer server(sc);

    const simclient::LoadConfig lc = testing::load_config(server, 10, 2.5, 0.3);
    boost::asio::io_context io;
    simclient::ParallelLoadRun run(io, lc, 3);
    ASSERT_EQ(run.threads(), 3);
    std::uint64_t sampled_snapshots = 0;
    std::uint64_t sampled_bytes_down = 0;
    int peak_sampled = 0;
    run.on_second([&](const simclient::SecondSample& s) {
        sampled_snapshots += s.snapshots;
        sampled_bytes_down += s.bytes_down;
        peak_sampled = std::max(peak_sampled, s.connected);
    });
    bool finished = false;
    run.on_finished([&] { finished = true; });
    run.start();
    io.run(); // returns once every shard's clients have said goodbye
    server.stop();

    ASSERT_TRUE(finished);
    const auto report = run.report();
    EXPECT_EQ(report.connected, 10);
    EXPECT_EQ(report.protocol_errors, 0u) << simclient::format_summary(report);
    EXPECT_TRUE(report.passed());
    EXPECT_EQ(report.peak_connected, 10);
    EXPECT_EQ(peak_sampled, 10);
    // The shards together are the scenario: ten clients, each named once, each its own
    // session (and so its own inputs).
    std::set<int> indexes;
    std::set<std::uint64_t> sessions;
    for (const auto& client : run.clients()) {
        indexes.insert(client->setup().index);
        sessions.insert(client->setup().session);
    }
    EXPECT_EQ(indexes, (std::set<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
    EXPECT_EQ(sessions.size(), 10u);
    // The merged seconds count what the sessions counted up to the run's end (the run
    // ends half a second after its last whole second, so the time series keeps its last
    // interval); after it, each session may still get a snapshot and its goodbye.
    EXPECT_LE(sampled_snapshots, report.snapshots);
    EXPECT_GE(sampled_snapshots + 10, report.snapshots);
    EXPECT_LE(sampled_bytes_down, report.bytes_down);
    EXPECT_GE(static_cast<double>(sampled_bytes_down),
              0.95 * static_cast<double>(report.bytes_down));
    EXPECT_EQ(server.stats().snapshots_sent, report.snapshots);
    EXPECT_EQ(server.stats().disconnects.at("client_quit"), 10u);
}

TEST(EndToEnd, StoppingAThreadedRunStopsEveryThreadWithTheReason) {
    server::ServerConfig sc;
    sc.bots = 10;
    testing::RunningServer server(sc);

    // 30 s, far longer than we wait: stop() ends it, as SIGINT does in dsoc-simclient
    const simclient::LoadConfig lc = testing::load_config(server, 8, 30.0, 0.0);
    boost::asio::io_context io;
    simclient::ParallelLoadRun run(io, lc, 2);
    std::vector<simclient::SecondSample> seconds;
    run.on_second([&](const simclient::SecondSample& s) { seconds.push_back(s); });
    boost::asio::steady_timer stop_after(io, std::chrono::milliseconds(1500));
    stop_after.async_wait([&](const boost::system::error_code&) { run.stop("told to stop"); });
    const auto before = std::chrono::steady_clock::now();
    run.start();
    io.run();
    const double took =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
    server.stop();

    EXPECT_LT(took, 10.0);
    const auto report = run.report();
    EXPECT_EQ(report.stopped_early, "told to stop");
    EXPECT_EQ(report.connected, 8);
    EXPECT_EQ(report.peak_connected, 8);
    EXPECT_EQ(report.failures, 0u) << simclient::format_summary(report);
    for (const auto& client : run.clients()) {
        EXPECT_TRUE(client->finished());
    }
    EXPECT_EQ(server.stats().disconnects.at("client_quit"), 8u);
    // The last second is the one the run stopped in, counted before the sessions left.
    ASSERT_GE(seconds.size(), 2u);
    EXPECT_NEAR(seconds.back().t_s, 1.5, 0.3);
    EXPECT_EQ(seconds.back().connected, 8);
}

} // namespace
} // namespace dsoc
