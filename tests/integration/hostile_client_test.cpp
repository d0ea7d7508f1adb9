// Hostile and broken clients are disconnected with a reason while well-behaved
// clients keep receiving snapshots at the tick rate.

#include "server_fixture.hpp"

#include "server/raw_client.hpp"

#include "dsoc/protocol/framing.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>
#include <vector>

namespace dsoc {
namespace {

namespace pb = protocol::pb;

using testing::client_hello;
using testing::GoodClients;
using testing::RawClient;

/// A hello of another protocol version than the server's.
pb::Envelope hello_of_version(std::uint32_t version) {
    pb::Envelope m = client_hello();
    m.mutable_client_hello()->set_protocol_version(version);
    return m;
}

class HostileClients : public ::testing::Test {
protected:
    static server::ServerConfig config() {
        server::ServerConfig c;
        c.bots = 40;
        c.handshake_timeout_ms = 400;
        c.max_frame_bytes = 1024;
        return c;
    }
};

TEST_F(HostileClients, AreDisconnectedWithReasonsWhileOthersKeepTheirSnapshots) {
    testing::RunningServer server(config());

    GoodClients good(testing::load_config(server, 4, 2.5, 0.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));

    // 1. Garbage: a plausible length, then bytes that are no protobuf message.
    RawClient garbage(server.port());
    std::vector<std::uint8_t> junk(4 + 60, 0xff);
    protocol::write_frame_header(junk.data(), 60);
    garbage.send_bytes(junk);

    // 2. An oversized frame (announces 1 MiB, limit 1 KiB).
    RawClient oversized(server.port());
    std::vector<std::uint8_t> big_header(4);
    protocol::write_frame_header(big_header.data(), 1024 * 1024);
    oversized.send_bytes(big_header);

    // 3. Connects and says nothing.
    RawClient silent(server.port());

    // 4. Speaks another protocol version.
    RawClient old_version(server.port());
    old_version.send_message(hello_of_version(99));

    // 5. Valid hello, then a NaN in its input.
    RawClient nan_input(server.port());
    nan_input.send_message(client_hello());
    pb::Envelope input;
    input.mutable_client_input()->set_view_yaw(std::nanf(""));
    nan_input.send_message(input);

    // 6. Sends a server-only message.
    RawClient impostor(server.port());
    impostor.send_message(client_hello());
    pb::Envelope fake;
    fake.mutable_snapshot()->set_server_tick(1);
    impostor.send_message(fake);

    const auto expect_reason = [](RawClient& client, pb::DisconnectReason reason,
                                  const char* what) {
        const auto d = client.read_until_closed();
        ASSERT_TRUE(d.has_value()) << what << ": no disconnect message";
        EXPECT_EQ(d->reason(), reason) << what << ": " << d->text();
        EXPECT_FALSE(d->text().empty()) << what;
    };
    expect_reason(garbage, pb::DISCONNECT_REASON_PROTOCOL_ERROR, "garbage");
    expect_reason(oversized, pb::DISCONNECT_REASON_FRAME_TOO_LARGE, "oversized");
    expect_reason(silent, pb::DISCONNECT_REASON_HANDSHAKE_TIMEOUT, "silent");
    expect_reason(old_version, pb::DISCONNECT_REASON_VERSION_MISMATCH, "old version");
    expect_reason(nan_input, pb::DISCONNECT_REASON_INVALID_INPUT, "nan input");
    expect_reason(impostor, pb::DISCONNECT_REASON_PROTOCOL_ERROR, "impostor");

    // The well-behaved clients kept getting snapshots at the tick rate throughout.
    testing::expect_served(good, 100.0);
    server.stop();

    const auto& d = server.stats().disconnects;
    EXPECT_EQ(d.at("protocol_error"), 2u);
    EXPECT_EQ(d.at("frame_too_large"), 1u);
    EXPECT_EQ(d.at("handshake_timeout"), 1u);
    EXPECT_EQ(d.at("version_mismatch"), 1u);
    EXPECT_EQ(d.at("invalid_input"), 1u);
}

TEST_F(HostileClients, ServerFullIsRefusedWithAReason) {
    auto c = config();
    c.max_clients = 1;
    testing::RunningServer server(c);
    RawClient first(server.port());
    first.send_message(client_hello());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    RawClient second(server.port());
    second.send_message(client_hello());
    const auto d = second.read_until_closed();
    ASSERT_TRUE(d.has_value());
    EXPECT_EQ(d->reason(), pb::DISCONNECT_REASON_SERVER_FULL);
}

/// Connections from `sources` (loopback addresses) that say nothing, in this order, left
/// a moment for the server to take them all.
std::vector<std::unique_ptr<RawClient>> silent_connections(std::uint16_t port,
                                                           std::vector<const char*> sources) {
    std::vector<std::unique_ptr<RawClient>> silent;
    for (const char* source : sources) {
        silent.push_back(std::make_unique<RawClient>(port, 0, source));
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    return silent;
}

TEST_F(HostileClients, ConnectionsThatSayNoHelloTakeNoClientsPlace) {
    // Silent connections (until their handshake timeout) once made a full server: a host
    // could keep every player out by holding max_clients of them.
    auto c = config();
    c.max_clients = 2;
    c.handshake_timeout_ms = 5000; // the silent ones wait all through the test
    testing::RunningServer server(c);
    const auto silent = silent_connections(server.port(), {nullptr, nullptr, nullptr, nullptr});
    RawClient first(server.port());
    RawClient second(server.port());
    first.send_message(client_hello());
    second.send_message(client_hello());
    EXPECT_TRUE(first.read_until_hello(std::chrono::seconds(3)));
    EXPECT_TRUE(second.read_until_hello(std::chrono::seconds(3)));
    server.stop();
    EXPECT_EQ(server.stats().disconnects.count("server_full"), 0u);
}

TEST_F(HostileClients, ASourceWithManyConnectionsWaitingMustSayItsHelloSoon) {
    auto c = config();
    c.max_pending_per_source = 3;
    c.handshake_timeout_ms = 5000; // the silent ones wait all through the test
    testing::RunningServer server(c);
    auto silent = silent_connections(server.port(), {nullptr, nullptr, nullptr});
    {
        // A fourth from the same address that says nothing is closed long before 5 s.
        const auto started = std::chrono::steady_clock::now();
        RawClient fourth(server.port());
        const auto closed = fourth.read_until_closed();
        const auto waited = std::chrono::steady_clock::now() - started;
        ASSERT_TRUE(closed.has_value());
        EXPECT_EQ(closed->reason(), pb::DISCONNECT_REASON_HANDSHAKE_TIMEOUT) << closed->text();
        EXPECT_LT(waited, std::chrono::milliseconds(2000));
    } // and closes its end
    // One that says its hello at once joins, as a load generator's clients do.
    RawClient talking(server.port());
    talking.send_message(client_hello());
    EXPECT_TRUE(talking.read_until_hello(std::chrono::seconds(3)));
    // A waiting connection that closes gives its place back (and one that joins does):
    // with one of the three silent ones gone, a fifth silent one gets the whole deadline.
    silent.erase(silent.begin());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    RawClient fifth(server.port());
    std::optional<pb::Disconnect> early;
    EXPECT_FALSE(fifth.read_until_hello(std::chrono::milliseconds(1500), &early));
    EXPECT_FALSE(early.has_value()) << early->text();
    server.stop();
    EXPECT_EQ(server.stats().disconnects.at("handshake_timeout"), 1u);
}

TEST_F(HostileClients, AtTheCapOfConnectionsWaitingTheOldestOfTheSourceHoldingTheMostMakesRoom) {
    auto c = config();
    c.max_pending_connections = 5;
    c.handshake_timeout_ms = 5000;
    testing::RunningServer server(c);
    const auto silent = silent_connections( // three from 127.0.0.1, two from .3
        server.port(), {"127.0.0.1", "127.0.0.1", "127.0.0.1", "127.0.0.3", "127.0.0.3"});
    RawClient newcomer(server.port(), 0, "127.0.0.4");
    newcomer.send_message(client_hello());
    EXPECT_TRUE(newcomer.read_until_hello(std::chrono::seconds(3)));
    const auto evicted = silent.front()->read_until_closed();
    ASSERT_TRUE(evicted.has_value());
    EXPECT_EQ(evicted->reason(), pb::DISCONNECT_REASON_TRY_AGAIN) << evicted->text();
    server.stop();
    EXPECT_EQ(server.stats().disconnects.at("try_again"), 1u);
}

} // namespace
} // namespace dsoc
