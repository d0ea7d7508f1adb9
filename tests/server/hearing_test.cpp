// Hearing and teams on a real server over loopback: the server's bots run (footsteps) and fire
// (shots), the simulated players fire too; every client is sent what it hears but does
// not see on the heard tier, and dsoc-simclient's decoder checks each snapshot: a
// heard-only entity with view angles, or with an exact pose in the audit, is a protocol
// error. The replication trace lists the heard-only entities of each client.

#include "dsoc/simclient/load_run.hpp"
#include "integration/server_fixture.hpp"
#include "server/raw_client.hpp"
#include "support/temp_dir.hpp"
#include "support/trace_checks.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

namespace dsoc {
namespace {

TEST(Hearing, SimulatedPlayersHearCoarseWithoutAnglesAndTheTraceSaysWhichOnesTheyHear) {
    const std::string trace_path = testing::run_temp_path("dsoc-hearing", ".jsonl");
    server::ServerConfig c;
    c.bots = 60;
    c.trace_file = trace_path;
    c.trace_every = 3;
    ASSERT_TRUE(c.sounds) << "sounds are on by default";
    testing::RunningServer server(c);
    simclient::LoadConfig lc = testing::load_config(server, 6, 3.0, 0.5);
    lc.audit_every_ticks = 1; // every snapshot's exact poses: none may be a heard one
    const simclient::LoadReport report = testing::run_load(lc);
    server.stop();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_EQ(report.protocol_errors, 0u) << simclient::format_summary(report);
    EXPECT_GT(report.audited_poses, 1000u);
    EXPECT_GT(report.entities_heard.mean, 0.5) << simclient::format_summary(report);
    EXPECT_GT(server.stats().heard_entities_sent, 100u);

    EXPECT_GT(testing::expect_heard_are_replicated(trace_path), 0u);
    std::filesystem::remove(trace_path);
}

} // namespace
} // namespace dsoc

namespace dsoc {
namespace {

TEST(Teams, TheServerHelloTellsAClientItsTeamTheOneItsEntityPlaysFor) {
    server::ServerConfig c;
    c.bots = 4; // entities 1..4; the players reserve 5 and 6 in hello order
    c.teams = 2;
    testing::RunningServer server(c);
    testing::RawClient first(server.port());
    first.send_message(testing::client_hello());
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    testing::RawClient second(server.port());
    second.send_message(testing::client_hello());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    server.stop();
    for (testing::RawClient* client : {&first, &second}) {
        client->read_until_closed();
        ASSERT_TRUE(client->hello_received());
    }
    EXPECT_EQ(first.hello().entity_id(), 5u);
    EXPECT_EQ(first.hello().team(), 1u); // (5 - 1) % 2 + 1
    EXPECT_EQ(second.hello().entity_id(), 6u);
    EXPECT_EQ(second.hello().team(), 2u);
}

} // namespace
} // namespace dsoc
