// A scaled-out game as an operator starts it (docs/scale-out.md): a real nats-server,
// dsoc-server --role world, two dsoc-server --role gateway and dsoc-simclient spread
// over both gateways, all child processes on loopback. Mid-run one gateway is killed
// (its clients reconnect to the other: failovers, not failures) and NATS restarts (the
// world and the gateway reconnect and carry on: the clients see a gap, not an error).
// And the world process killed and replaced: the gateways follow the new one, ending
// each session once (world_restarted), and the clients come back as new players. And a
// gateway with no entity ids tells its clients to try again, not that it is full.
// Skipped, with the reason, where nats-server is absent (scripts/setup installs it).

#include "program_paths.hpp"
#include "support/child_process.hpp"
#include "support/eventually.hpp"
#include "support/http_client.hpp"
#include "support/nats_server.hpp"
#include "support/temp_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace dsoc::testing {
namespace {

using json = nlohmann::json;
using namespace std::chrono_literals;

/// The number after `label` in `text` (e.g. "listening on port 4242"), or -1.
long number_after(const std::string& text, const std::string& label) {
    std::smatch match;
    if (std::regex_search(text, match, std::regex(label + R"( (\d+))"))) {
        return std::stol(match[1].str());
    }
    return -1;
}

/// A Prometheus sample's value in `metrics`, or -1 when absent.
double sample(const std::string& metrics, const std::string& name) {
    std::smatch match;
    if (std::regex_search(metrics, match, std::regex("\n" + name + R"( ([0-9.e+]+))"))) {
        return std::stod(match[1].str());
    }
    return -1.0;
}

/// How many times `needle` occurs in `text`.
std::size_t occurrences(const std::string& text, const std::string& needle) {
    std::size_t count = 0;
    for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) {
        ++count;
    }
    return count;
}

std::vector<std::string> world_process(const std::string& nats) {
    return {program("dsoc-server"),
            "--role",
            "world",
            "--nats-url",
            nats,
            "--world-name",
            "e2e",
            "--map",
            "gen:rooms:1",
            "--bots",
            "4",
            "--metrics-port",
            "0"};
}

std::vector<std::string> gateway(const std::string& nats) {
    return light_server(
        {"--role", "gateway", "--nats-url", nats, "--world-name", "e2e", "--metrics-port", "0"});
}

std::string gateway_metrics(const ChildProcess& g) {
    return http_body(
        http_get(static_cast<std::uint16_t>(number_after(g.out(), "metrics on port")), "/metrics"));
}

TEST(ScaleOut, GatewaysServeOneWorldThroughAKilledGatewayAndANatsRestart) {
    if (nats_server_binary().empty()) {
        GTEST_SKIP() << kNoNatsServer;
    }
    NatsServer nats;
    ChildProcess world(world_process(nats.url()));
    ASSERT_TRUE(world.wait_for_output("publishing on dsoc.e2e.tick")) << world.err();
    ChildProcess first(gateway(nats.url()));
    ChildProcess second(gateway(nats.url()));
    ASSERT_TRUE(first.wait_for_output("listening on port")) << first.err();
    ASSERT_TRUE(second.wait_for_output("listening on port")) << second.err();
    const long first_port = number_after(first.out(), "listening on port");
    const long second_port = number_after(second.out(), "listening on port");
    const long second_metrics = number_after(second.out(), "metrics on port");
    ASSERT_GT(second_metrics, 0) << second.out();
    for (const ChildProcess* g : {&first, &second}) {
        // Its first ids: asked for at its first world tick (a client before is told to try
        // again, a failover).
        ASSERT_TRUE(eventually(
            [&] { return sample(gateway_metrics(*g), "dsoc_gateway_id_blocks_total") >= 1.0; }));
    }

    const TempDir files("dsoc-scale-out");
    ChildProcess clients(
        {program("dsoc-simclient"), "--quiet", "--report", files.path("report.json"), "--server",
         "127.0.0.1:" + std::to_string(first_port) + ",127.0.0.1:" + std::to_string(second_port),
         "--clients", "6", "--ramp-up", "0.5", "--duration", "13"});
    std::this_thread::sleep_for(3s);
    first.signal(SIGKILL); // its three clients hear nothing more, then fail over
    std::this_thread::sleep_for(1s);
    nats.stop();
    std::this_thread::sleep_for(500ms);
    nats.start(); // the same port: world and gateway reconnect by themselves

    EXPECT_EQ(clients.wait(30s), 0) << clients.out() << clients.err();
    std::ifstream in(files.path("report.json"));
    const json report = json::parse(in, nullptr, false);
    ASSERT_TRUE(report.is_object()) << clients.out();
    EXPECT_EQ(report["failovers"], 3) << report.dump(1);
    EXPECT_EQ(report["failures"], 0) << report.dump(1);
    EXPECT_EQ(report["unexpected_disconnects"], 0);
    EXPECT_EQ(report["protocol_errors"], 0);
    EXPECT_EQ(report["missing_own_entity"], 0);
    EXPECT_GT(report["audited_poses"].get<int>(), 0); // the replicas match the world's poses

    const std::string metrics =
        http_body(http_get(static_cast<std::uint16_t>(second_metrics), "/metrics"));
    EXPECT_GE(sample(metrics, "dsoc_gateway_nats_reconnects_total"), 1.0) << metrics;
    EXPECT_GT(sample(metrics, "dsoc_gateway_world_ticks_total"), 200.0) << metrics;
    EXPECT_EQ(sample(metrics, "dsoc_gateway_bad_messages_total"), 0.0) << metrics;

    // Six clients, and three again after their failover: nine joined, and all have left
    // (the killed gateway's three when its heartbeat stopped) once the surviving
    // gateway's leaves have reached the world's next step.
    const long world_metrics = number_after(world.out(), "metrics on port");
    ASSERT_GT(world_metrics, 0) << world.out();
    const auto world_sample = [&](const std::string& name) {
        return sample(http_body(http_get(static_cast<std::uint16_t>(world_metrics), "/metrics")),
                      name);
    };
    EXPECT_TRUE(eventually([&] { return world_sample("dsoc_world_leaves_total") == 9.0; }, 10s))
        << world_sample("dsoc_world_leaves_total");
    EXPECT_EQ(world_sample("dsoc_world_joins_total"), 9.0);
    EXPECT_EQ(world_sample("dsoc_world_gateways_lost_total"), 1.0);
    second.signal(SIGTERM);
    EXPECT_EQ(second.wait(10s), 0) << second.err();
    world.signal(SIGTERM);
    EXPECT_EQ(world.wait(10s), 0) << world.err();
    EXPECT_NE(world.out().find("9 players joined, 9 left"), std::string::npos) << world.out();
}

/// A gateway's /metrics.
TEST(ScaleOut, ARestartedWorldEndsEachSessionOnceAndTheClientsComeBack) {
    if (nats_server_binary().empty()) {
        GTEST_SKIP() << kNoNatsServer;
    }
    NatsServer nats;
    auto world = std::make_unique<ChildProcess>(world_process(nats.url()));
    ASSERT_TRUE(world->wait_for_output("publishing on dsoc.e2e.tick", 20s)) << world->err();
    ChildProcess first(gateway(nats.url()));
    ChildProcess second(gateway(nats.url()));
    for (ChildProcess* g : {&first, &second}) {
        ASSERT_TRUE(g->wait_for_output("metrics on port", 20s)) << g->err();
        ASSERT_TRUE(g->wait_for_output("listening on port", 20s)) << g->err();
        // Its first ids come from the first world (the only one ticking yet).
        ASSERT_TRUE(eventually(
            [&] { return sample(gateway_metrics(*g), "dsoc_gateway_id_blocks_total") >= 1.0; }));
    }
    // The next world process starts now, beside the first, so that its start-up (however
    // slow) is not part of the outage: the gateways take nothing from it while the first
    // lives, and follow it once the first has been silent WorldFeed::kWorldSilence. The
    // wait for it is bounded.
    auto next = std::make_unique<ChildProcess>(world_process(nats.url()));
    ASSERT_TRUE(next->wait_for_output("publishing on dsoc.e2e.tick", 20s)) << next->err();

    const TempDir files("dsoc-scale-out-restart");
    ChildProcess clients(
        {program("dsoc-simclient"), "--quiet", "--report", files.path("report.json"), "--server",
         "127.0.0.1:" + std::to_string(number_after(first.out(), "listening on port")) +
             ",127.0.0.1:" + std::to_string(number_after(second.out(), "listening on port")),
         "--clients", "6", "--ramp-up", "0.5", "--duration", "7"});
    std::this_thread::sleep_for(2500ms);
    world->signal(SIGKILL); // no leave, no goodbye: its ticks stop
    (void)world->wait(5s);

    EXPECT_EQ(clients.wait(30s), 0) << clients.out() << clients.err();
    std::ifstream in(files.path("report.json"));
    const json report = json::parse(in, nullptr, false);
    ASSERT_TRUE(report.is_object()) << clients.out();
    // Causes, not counts (how many sessions a restart catches, and where their clients
    // land, depend on timing): no session failed, and every one the restart ended
    // failed over and came back.
    EXPECT_EQ(report["failures"], 0) << report.dump(1);
    EXPECT_EQ(report["unexpected_disconnects"], 0);
    EXPECT_EQ(report["protocol_errors"], 0);
    EXPECT_EQ(report["missing_own_entity"], 0);
    EXPECT_GT(report["audited_poses"].get<int>(), 0); // the new world's poses, audited
    const int restarted = report["disconnect_reasons"].value("world_restarted", 0);
    EXPECT_GE(restarted, 1) << report.dump(1);
    EXPECT_GE(report["failovers"].get<int>(), restarted) << report.dump(1);

    double ended = 0.0; // sessions the gateways ended with world_restarted
    for (ChildProcess* g : {&first, &second}) {
        const std::string metrics = gateway_metrics(*g);
        EXPECT_EQ(sample(metrics, "dsoc_gateway_world_restarts_total"), 1.0) << metrics;
        EXPECT_EQ(sample(metrics, "dsoc_gateway_bad_messages_total"), 0.0) << metrics;
        ended +=
            std::max(0.0, sample(metrics, R"(dsoc_disconnects_total\{reason="world_restarted"\})"));
        EXPECT_EQ(occurrences(g->err(), "world 'e2e' restarted"), 1u) << g->err(); // logged once
    }
    EXPECT_EQ(ended, restarted); // each session ended once, and its client knew why
    // The new world saw every ended session's client join again through the gateways,
    // and nothing of the old world's sessions, before or after the switch (no input or
    // leave under an id it had not handed out, no reservation for the old one).
    const long world_metrics = number_after(next->out(), "metrics on port");
    ASSERT_GT(world_metrics, 0) << next->out();
    const auto world_sample = [&](const std::string& name) {
        return sample(http_body(http_get(static_cast<std::uint16_t>(world_metrics), "/metrics")),
                      name);
    };
    const double joins = world_sample("dsoc_world_joins_total");
    EXPECT_GE(joins, restarted);
    EXPECT_EQ(world_sample("dsoc_world_for_strangers_total"), 0.0);
    EXPECT_EQ(world_sample("dsoc_world_bad_messages_total"), 0.0);
    EXPECT_GT(world_sample("dsoc_world_other_instance_total"), 0.0); // the first's gateways
    first.signal(SIGTERM);
    second.signal(SIGTERM);
    EXPECT_EQ(first.wait(10s), 0) << first.err();
    EXPECT_EQ(second.wait(10s), 0) << second.err();
    EXPECT_TRUE(eventually([&] { return world_sample("dsoc_world_leaves_total") == joins; }));
    next->signal(SIGTERM);
    EXPECT_EQ(next->wait(10s), 0) << next->err();
    const auto n = std::to_string(static_cast<long>(joins));
    EXPECT_NE(next->out().find(n + " players joined, " + n + " left"), std::string::npos)
        << next->out();
}

TEST(ScaleOut, AGatewayWithoutIdsAsksItsClientsToTryAgain) {
    if (nats_server_binary().empty()) {
        GTEST_SKIP() << kNoNatsServer;
    }
    NatsServer nats;
    ChildProcess lone(gateway(nats.url())); // no world process: no ids will come
    ASSERT_TRUE(lone.wait_for_output("listening on port", 20s)) << lone.err();
    const TempDir files("dsoc-scale-out-try-again");
    ChildProcess clients(
        {program("dsoc-simclient"), "--quiet", "--report", files.path("report.json"), "--server",
         "127.0.0.1:" + std::to_string(number_after(lone.out(), "listening on port")), "--clients",
         "1", "--duration", "5"});
    EXPECT_NE(clients.wait(30s), 0); // no client could connect
    std::ifstream in(files.path("report.json"));
    const json report = json::parse(in, nullptr, false);
    ASSERT_TRUE(report.is_object()) << clients.out() << clients.err();
    // Not server_full (a failure at once): the client came back, twice, before it gave
    // up (dsoc-simclient: a client that fails before its hello at every server twice).
    EXPECT_EQ(report["disconnect_reasons"], json({{"try_again", 3}})) << report.dump(1);
    EXPECT_EQ(report["failovers"], 2) << report.dump(1);
    EXPECT_EQ(report["failures_by_reason"], json({{"try_again", 1}})) << report.dump(1);
    lone.signal(SIGTERM);
    EXPECT_EQ(lone.wait(10s), 0) << lone.err();
}

} // namespace
} // namespace dsoc::testing
