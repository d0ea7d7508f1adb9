// Spectating (ClientInput.watch) on a real server over loopback: a client that watches
// another player is sent that player's view, with its own entity, and nothing more; when
// it stops watching it is back to its own view. Judged from the server's replication
// trace, with the distance policy (whose set is a function of the eye) and the
// occlusion policy (of the viewer entity's reachable region, no temporal state).

#include "dsoc/simclient/load_run.hpp"
#include "dsoc/trace/trace_reader.hpp"
#include "integration/server_fixture.hpp"
#include "server/raw_client.hpp"
#include "support/temp_dir.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iterator>
#include <thread>
#include <vector>

namespace dsoc {
namespace {

using testing::client_hello;
using testing::RawClient;
using testing::RunningServer;

protocol::pb::Envelope input_watching(std::uint64_t tick, std::uint32_t entity) {
    protocol::pb::Envelope m;
    m.mutable_client_input()->set_tick(tick);
    m.mutable_client_input()->set_watch(entity);
    return m;
}

std::vector<std::uint32_t> with(std::vector<std::uint32_t> ids, std::uint32_t id) {
    if (!std::binary_search(ids.begin(), ids.end(), id)) {
        ids.insert(std::upper_bound(ids.begin(), ids.end(), id), id);
    }
    return ids;
}

class Spectating : public ::testing::TestWithParam<interest::PolicyKind> {};

TEST_P(Spectating, AClientWatchingAPlayerIsSentThatPlayersViewThenItsOwnAgain) {
    const std::string trace_path = testing::run_temp_path("dsoc-spectate", ".jsonl");
    server::ServerConfig c;
    c.bots = 40; // entity ids 1..40; the players reserve 41 and 42 in hello order
    c.policy = GetParam();
    c.distance_radius = 600.0f;
    c.trace_file = trace_path;
    c.trace_every = 1;
    constexpr std::uint32_t kPlayer = 41;
    constexpr std::uint32_t kSpectator = 42;
    {
        RunningServer server(c);
        RawClient player(server.port());
        player.send_message(client_hello());
        std::this_thread::sleep_for(std::chrono::milliseconds(150));
        RawClient spectator(server.port());
        spectator.send_message(client_hello());
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        spectator.send_message(input_watching(1, kPlayer));
        std::this_thread::sleep_for(std::chrono::milliseconds(700));
        spectator.send_message(input_watching(2, 0));
        std::this_thread::sleep_for(std::chrono::milliseconds(400));
        server.stop();
    }

    trace::TraceReader reader;
    ASSERT_TRUE(reader.open(trace_path)) << reader.error();
    trace::TraceTick tick;
    enum class Phase { before, watching, after } phase = Phase::before;
    int ticks[3] = {0, 0, 0};
    int own_view_differs = 0;
    while (reader.next(tick)) {
        const trace::TraceClient* a = nullptr;
        const trace::TraceClient* b = nullptr;
        for (const trace::TraceClient& client : tick.clients) {
            a = client.entity == kPlayer ? &client : a;
            b = client.entity == kSpectator ? &client : b;
        }
        if (a == nullptr || b == nullptr) {
            continue;
        }
        const bool watching = a->eye == b->eye;
        if (watching) {
            ASSERT_NE(phase, Phase::after) << "watching again at tick " << tick.t;
            phase = Phase::watching;
            // The player's set, plus the spectator's own entity: nothing more.
            EXPECT_EQ(with(b->replicated, kSpectator), with(a->replicated, kSpectator))
                << "tick " << tick.t;
        } else {
            phase = phase == Phase::before ? Phase::before : Phase::after;
            own_view_differs += with(b->replicated, kSpectator) != with(a->replicated, kSpectator);
        }
        ++ticks[static_cast<int>(phase)];
    }
    EXPECT_TRUE(reader.error().empty()) << reader.error();
    EXPECT_GE(ticks[0], 3) << "ticks before watching";
    EXPECT_GE(ticks[1], 10) << "ticks watching";
    EXPECT_GE(ticks[2], 3) << "ticks after watching";
    // The check means something: from its own eye the spectator's set is another one.
    EXPECT_GT(own_view_differs, 0);
    std::filesystem::remove(trace_path);
}

/// Three wanderers, then three spectators (behaviour "spectator"), against `server` for
/// about 3 s: each spectator watches a player it knows and switches every 5-10 s or when
/// that player is gone.
simclient::LoadConfig wanderers_and_spectators(const testing::RunningServer& server) {
    simclient::LoadConfig lc;
    lc.port = server.port();
    lc.progress = false;
    simclient::Scenario scenario;
    scenario.stages = {{0.0, 6}, {3.0, 6}};
    scenario.groups.resize(2);
    scenario.groups[0].name = "wanderers";
    scenario.groups[1].name = "spectators";
    scenario.groups[1].behaviour = simclient::Behaviour::spectator;
    lc.scenario = scenario;
    return lc;
}

TEST(Spectating, SimulatedSpectatorsWatchPlayersAndEverySwitchPassesTheProtocolChecks) {
    // Against the server's default policy; the client checks every snapshot (enters only
    // of unknown entities, leaves only of known ones, its own entity always there).
    server::ServerConfig c;
    c.bots = 40;
    testing::RunningServer server(c);
    simclient::LoadConfig lc = wanderers_and_spectators(server);
    lc.transport = simclient::LoadConfig::Transport::tcp;
    const simclient::LoadReport report = testing::run_load(lc);
    server.stop();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    // Three spectators for about 3 s at 30 Hz, once they know a player.
    EXPECT_GT(server.stats().spectating_client_ticks, 100u);
}

TEST(Spectating, SpectatorsDecodeTheirSnapshotsWhenTheOtherClientsAcknowledgeThemUnread) {
    // One client in 1,000 checks (LoadConfig::check_every): each group's first, and none
    // else here. A spectator picks whom to watch from the players it knows, so all three
    // decode anyway; were only the first to, fewer than 100 client-ticks would spectate.
    server::ServerConfig c;
    c.bots = 40;
    testing::RunningServer server(c);
    simclient::LoadConfig lc = wanderers_and_spectators(server);
    lc.check_every = 1000;
    const simclient::LoadReport report = testing::run_load(lc);
    server.stop();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_LT(report.checked_snapshots, report.snapshots); // two wanderers discarded theirs
    EXPECT_GT(server.stats().spectating_client_ticks, 130u);
}

INSTANTIATE_TEST_SUITE_P(Policies, Spectating,
                         ::testing::Values(interest::PolicyKind::distance,
                                           interest::PolicyKind::occlusion),
                         [](const ::testing::TestParamInfo<interest::PolicyKind>& p) {
                             return std::string(interest::name_of(p.param));
                         });

} // namespace
} // namespace dsoc
