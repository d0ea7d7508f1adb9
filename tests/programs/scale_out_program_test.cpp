// A scaled-out game as an operator starts it (docs/scale-out.md): a real nats-server,
// dsoc-server --role world, two dsoc-server --role gateway and dsoc-simclient spread
// over both gateways, all child processes on loopback. Mid-run one gateway is killed
// (its clients reconnect to the other: failovers, not failures) and NATS restarts (the
// world and the gateway reconnect and carry on: the clients see a gap, not an error).
// And the world process killed and started again: the gateways follow the new one,
// ending each session once (world_restarted), and the clients come back as new players.
// Skipped, with the reason, where nats-server is absent (scripts/setup installs it).

#include "program_paths.hpp"
#include "support/child_process.hpp"
#include "support/eventually.hpp"
#include "support/http_client.hpp"
#include "support/nats_server.hpp"
#include "support/temp_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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

TEST(ScaleOut, ARestartedWorldEndsEachSessionOnceAndTheClientsComeBack) {
    if (nats_server_binary().empty()) {
        GTEST_SKIP() << kNoNatsServer;
    }
    NatsServer nats;
    auto world = std::make_unique<ChildProcess>(world_process(nats.url()));
    ASSERT_TRUE(world->wait_for_output("publishing on dsoc.e2e.tick")) << world->err();
    ChildProcess first(gateway(nats.url()));
    ChildProcess second(gateway(nats.url()));
    ASSERT_TRUE(first.wait_for_output("metrics on port")) << first.err();
    ASSERT_TRUE(second.wait_for_output("metrics on port")) << second.err();
    ASSERT_TRUE(first.wait_for_output("listening on port")) << first.err();
    ASSERT_TRUE(second.wait_for_output("listening on port")) << second.err();

    const TempDir files("dsoc-scale-out-restart");
    ChildProcess clients(
        {program("dsoc-simclient"), "--quiet", "--report", files.path("report.json"), "--server",
         "127.0.0.1:" + std::to_string(number_after(first.out(), "listening on port")) +
             ",127.0.0.1:" + std::to_string(number_after(second.out(), "listening on port")),
         "--clients", "6", "--ramp-up", "0.5", "--duration", "7"});
    std::this_thread::sleep_for(2500ms);
    world->signal(SIGKILL); // no leave, no goodbye: its ticks stop
    (void)world->wait(5s);
    world = std::make_unique<ChildProcess>(world_process(nats.url())); // ticks from 1 again
    ASSERT_TRUE(world->wait_for_output("publishing on dsoc.e2e.tick")) << world->err();

    EXPECT_EQ(clients.wait(30s), 0) << clients.out() << clients.err();
    std::ifstream in(files.path("report.json"));
    const json report = json::parse(in, nullptr, false);
    ASSERT_TRUE(report.is_object()) << clients.out();
    EXPECT_EQ(report["failovers"], 6) << report.dump(1); // every session once
    EXPECT_EQ(report["failures"], 0) << report.dump(1);
    EXPECT_EQ(report["unexpected_disconnects"], 0);
    EXPECT_EQ(report["protocol_errors"], 0);
    EXPECT_EQ(report["missing_own_entity"], 0);
    EXPECT_GT(report["audited_poses"].get<int>(), 0); // the new world's poses, audited

    for (ChildProcess* g : {&first, &second}) {
        const std::string metrics = http_body(http_get(
            static_cast<std::uint16_t>(number_after(g->out(), "metrics on port")), "/metrics"));
        EXPECT_EQ(sample(metrics, "dsoc_gateway_world_restarts_total"), 1.0) << metrics;
        EXPECT_EQ(sample(metrics, "dsoc_gateway_bad_messages_total"), 0.0) << metrics;
        EXPECT_EQ(sample(metrics, R"(dsoc_disconnects_total\{reason="world_restarted"\})"), 3.0)
            << metrics;
        EXPECT_EQ(occurrences(g->err(), "world 'e2e' restarted"), 1u) << g->err(); // logged once
    }
    // The new world saw six players join through the gateways, and nothing of the old
    // world's sessions (no input or leave under an id it had not handed out).
    const long world_metrics = number_after(world->out(), "metrics on port");
    ASSERT_GT(world_metrics, 0) << world->out();
    const std::string metrics =
        http_body(http_get(static_cast<std::uint16_t>(world_metrics), "/metrics"));
    EXPECT_EQ(sample(metrics, "dsoc_world_joins_total"), 6.0) << metrics;
    EXPECT_EQ(sample(metrics, "dsoc_world_for_strangers_total"), 0.0) << metrics;
    first.signal(SIGTERM);
    second.signal(SIGTERM);
    EXPECT_EQ(first.wait(10s), 0) << first.err();
    EXPECT_EQ(second.wait(10s), 0) << second.err();
    EXPECT_TRUE(eventually([&] {
        return sample(http_body(http_get(static_cast<std::uint16_t>(world_metrics), "/metrics")),
                      "dsoc_world_leaves_total") == 6.0;
    }));
    world->signal(SIGTERM);
    EXPECT_EQ(world->wait(10s), 0) << world->err();
    EXPECT_NE(world->out().find("6 players joined, 6 left"), std::string::npos) << world->out();
}

} // namespace
} // namespace dsoc::testing
