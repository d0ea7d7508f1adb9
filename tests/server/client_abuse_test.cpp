// Slow, silent, flooding, unauthorized and malformed clients each get a disconnect
// with a reason, and the well-behaved clients running beside them keep receiving
// their snapshots at the tick rate throughout.

#include "integration/server_fixture.hpp"
#include "server/raw_client.hpp"

#include "dsoc/protocol/connect_token.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace dsoc {
namespace {

namespace pb = protocol::pb;
using testing::client_hello;
using testing::expect_served;
using testing::GoodClients;
using testing::RawClient;
using testing::RunningServer;

constexpr double kGoodSeconds = 2.0;

server::ServerConfig base_config() {
    server::ServerConfig c;
    c.bots = 40;
    c.handshake_timeout_ms = 400;
    c.max_frame_bytes = 1024;
    return c;
}

void expect_reason(RawClient& client, pb::DisconnectReason reason, const char* text_part) {
    const auto d = client.read_until_closed();
    ASSERT_TRUE(d.has_value()) << "no disconnect message; expected "
                               << protocol::disconnect_reason_name(reason);
    EXPECT_EQ(protocol::disconnect_reason_name(d->reason()),
              protocol::disconnect_reason_name(reason))
        << d->text();
    EXPECT_NE(d->text().find(text_part), std::string::npos) << d->text();
}

/// A token key in a temporary file, for servers that check tokens.
class KeyFile {
public:
    KeyFile() : key_(protocol::generate_token_key()) {
        path_ = std::filesystem::temp_directory_path() /
                ("dsoc-test-" + std::to_string(::getpid()) + "-" +
                 std::to_string(reinterpret_cast<std::uintptr_t>(this)) + ".key");
        std::ofstream(path_) << protocol::format_token_key(key_) << "\n";
    }
    ~KeyFile() { std::filesystem::remove(path_); }
    KeyFile(const KeyFile&) = delete;
    KeyFile& operator=(const KeyFile&) = delete;
    [[nodiscard]] std::string path() const { return path_.string(); }
    [[nodiscard]] const protocol::TokenKey& key() const { return key_; }

private:
    protocol::TokenKey key_;
    std::filesystem::path path_;
};

TEST(ClientAbuse, SlowReaderHasSnapshotsDroppedStaysBoundedAndIsDisconnected) {
    auto c = base_config();
    c.bots = 150;
    c.policy = interest::PolicyKind::broadcast; // large snapshots: every bot moves every tick
    c.socket_send_buffer_bytes = 4096;          // small kernel buffers: the backlog shows at once
    c.slow_client_timeout_ms = 800;
    RunningServer server(c);
    GoodClients good(server.port(), kGoodSeconds + 1.0);

    RawClient slow(server.port(), 4096);
    slow.send_message(client_hello());
    // It reads nothing while the server would have queued ~60 snapshots for it.
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    const auto d = slow.read_until_closed();
    expect_served(good);
    server.stop();

    const auto& stats = server.stats();
    EXPECT_EQ(stats.disconnects.count("too_slow"), 1u);
    // It resumed reading well within a second of being dropped: the reason reached it.
    ASSERT_TRUE(d.has_value()) << "no disconnect message";
    EXPECT_EQ(protocol::disconnect_reason_name(d->reason()), "too_slow") << d->text();
    EXPECT_EQ(slow.trailing_bytes(), 0u) << "the connection ended inside a frame";
    // Stale snapshots were dropped, not queued: the queue never held more than about
    // one snapshot (a few KiB here), far below what 1.5 s of snapshots would take.
    EXPECT_GE(stats.snapshots_dropped, 10u);
    EXPECT_LE(stats.peak_queued_bytes, 32u * 1024u);
}

TEST(ClientAbuse, StalledReaderThatReadsAgainLateReceivesTooSlowThenEndOfFile) {
    auto c = base_config();
    c.bots = 150;
    c.policy = interest::PolicyKind::broadcast;
    c.socket_send_buffer_bytes = 4096;
    c.slow_client_timeout_ms = 300;
    RunningServer server(c);

    RawClient slow(server.port(), 4096);
    slow.send_message(client_hello());
    // Stalled through the drop (about 300 ms after its first snapshot) and well past
    // the 1 s grace after it, when the server has closed the socket...
    std::this_thread::sleep_for(std::chrono::milliseconds(2500));
    // ...then reading again: the rest of the frame that was being written, the reason,
    // end-of-file; no frame cut off.
    const auto d = slow.read_until_closed();
    server.stop();

    EXPECT_EQ(server.stats().disconnects.count("too_slow"), 1u);
    ASSERT_TRUE(d.has_value()) << "no disconnect message after " << slow.snapshots()
                               << " snapshots; " << slow.trailing_bytes()
                               << " bytes of a cut-off frame";
    EXPECT_EQ(protocol::disconnect_reason_name(d->reason()), "too_slow") << d->text();
    EXPECT_EQ(slow.trailing_bytes(), 0u) << "the connection ended inside a frame";
}

TEST(ClientAbuse, SnapshotsTheKernelTakesInPartArriveWhole) {
    // At the hand-over a frame goes straight to the kernel, which may take only part of
    // it; the rest must follow through the session's queue, in order, before anything
    // else. The first snapshot here (400 entities entering) is larger than the socket's
    // buffers on both sides, and the reader is slow.
    auto c = base_config();
    c.bots = 400;
    c.policy = interest::PolicyKind::broadcast; // every bot in every snapshot
    c.socket_send_buffer_bytes = 4096;          // small kernel buffers
    c.slow_client_timeout_ms = 10'000;          // slow, but never dropped here
    RunningServer server(c);

    RawClient reader(server.port(), 4096);
    reader.send_message(client_hello());
    std::optional<pb::Disconnect> d;
    std::thread read([&] { d = reader.read_until_closed(1024, std::chrono::milliseconds(5)); });
    std::this_thread::sleep_for(std::chrono::milliseconds(2000));
    server.stop();
    read.join();

    EXPECT_GT(server.stats().snapshot_writes_queued, 0u)
        << "the kernel took every frame whole: the test did not reach the partial write";
    EXPECT_GE(reader.snapshots(), 10u);
    EXPECT_EQ(reader.undecodable_frames(), 0u);
    EXPECT_EQ(reader.trailing_bytes(), 0u) << "the connection ended inside a frame";
    ASSERT_TRUE(d.has_value()) << "no disconnect message";
    EXPECT_EQ(protocol::disconnect_reason_name(d->reason()), "server_shutdown") << d->text();
    EXPECT_EQ(server.stats().disconnects.count("too_slow"), 0u);
}

TEST(ClientAbuse, GoodClientsGetEveryFrameWholeAndATicksPartsAddUp) {
    // The other side of the hand-over's direct writes: clients that keep up have every
    // frame taken whole by the kernel (nothing queued), every byte they receive was
    // counted as sent, and the three parts of a tick in /metrics add up to its cost.
    auto c = base_config();
    c.policy = interest::PolicyKind::broadcast;
    RunningServer server(c);
    GoodClients good(server.port(), 1.5, std::nullopt, 4);
    const auto report = good.finish();
    server.stop();

    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    const auto& stats = server.stats();
    EXPECT_GE(stats.snapshots_sent, 4u * 30u);
    EXPECT_EQ(stats.snapshot_writes_queued, 0u);
    EXPECT_GT(report.bytes_down, 0u);
    EXPECT_LE(report.bytes_down, stats.bytes_sent) << "a client received bytes never counted";
    const std::uint64_t ticks = stats.tick_duration.count();
    EXPECT_GE(ticks, 30u);
    EXPECT_EQ(stats.prepare_duration.count(), ticks);
    EXPECT_EQ(stats.culling_duration.count(), ticks);
    EXPECT_EQ(stats.handover_duration.count(), ticks);
    const double parts =
        stats.prepare_duration.sum() + stats.culling_duration.sum() + stats.handover_duration.sum();
    EXPECT_NEAR(parts, stats.tick_duration.sum(), 1e-6 * static_cast<double>(ticks));
}

/// The I/O thread gathers socket events between wakeups (io_loop.hpp); the end of a
/// tick's parallel phase wakes it, so the hand-over starts at once instead of when the
/// gather that began with the tick ends (with a few clients a phase is over long before).
TEST(ClientAbuse, TheHandOverDoesNotWaitOutTheIoThreadsGather) {
    server::ServerConfig c = base_config();
    c.tick_rate = 10;
    c.io_gather_us = 20'000;                          // the most validate() allows
    for (const auto& problem : server::validate(c)) { // the fixture fills in the rest
        EXPECT_EQ(problem.find("io_gather_us"), std::string::npos) << problem;
    }
    RunningServer server(c);
    {
        GoodClients good(server.port(), kGoodSeconds);
        good.finish();
    }
    server.stop();
    const auto& wait = server.stats().handover_wait;
    ASSERT_GE(wait.count(), 15u);
    // Without the wake the mean is most of a gather (13 ms when it was tried).
    EXPECT_LT(wait.sum() / static_cast<double>(wait.count()), 0.005);
}

TEST(ClientAbuse, ConnectionsWithoutHelloAreClosedAtTheDeadline) {
    RunningServer server(base_config());
    GoodClients good(server.port(), kGoodSeconds);
    RawClient silent(server.port());
    RawClient half_header(server.port()); // slowloris: two bytes of a frame header, then nothing
    const std::array<std::uint8_t, 2> two_bytes{16, 0};
    half_header.send_bytes(two_bytes);
    const auto started = std::chrono::steady_clock::now();
    expect_reason(silent, pb::DISCONNECT_REASON_HANDSHAKE_TIMEOUT, "400 ms");
    expect_reason(half_header, pb::DISCONNECT_REASON_HANDSHAKE_TIMEOUT, "400 ms");
    const auto waited = std::chrono::steady_clock::now() - started;
    EXPECT_GE(waited, std::chrono::milliseconds(350));
    EXPECT_LT(waited, std::chrono::milliseconds(1500));
    expect_served(good);
}

TEST(ClientAbuse, InputFloodIsCappedThenDisconnected) {
    auto c = base_config();
    c.max_inputs_per_second = 60;
    RunningServer server(c);
    GoodClients good(server.port(), kGoodSeconds);
    RawClient flood(server.port());
    flood.send_message(client_hello());
    std::vector<std::uint8_t> burst;
    for (int i = 0; i < 2000; ++i) {
        pb::Envelope input;
        input.mutable_client_input()->set_tick(static_cast<std::uint64_t>(i));
        input.mutable_client_input()->set_move_x(1.0f);
        protocol::encode_frame(input, burst);
    }
    flood.send_bytes(burst);
    expect_reason(flood, pb::DISCONNECT_REASON_INPUT_FLOOD, "input flood");
    expect_served(good);
    server.stop();
    // 60 accepted (the burst allowance), then 61 drops make a flood.
    EXPECT_EQ(server.stats().inputs_dropped, 61u);
}

TEST(ClientAbuse, NonFiniteInputIsRefusedAndOutOfRangeInputIsClamped) {
    RunningServer server(base_config());
    GoodClients good(server.port(), kGoodSeconds);

    RawClient nan_input(server.port());
    nan_input.send_message(client_hello());
    pb::Envelope nan;
    nan.mutable_client_input()->set_view_yaw(std::nanf(""));
    nan_input.send_message(nan);

    RawClient inf_input(server.port());
    inf_input.send_message(client_hello());
    pb::Envelope inf;
    inf.mutable_client_input()->set_move_y(-HUGE_VALF);
    inf_input.send_message(inf);

    RawClient wild_input(server.port()); // finite but out of range: clamped, stays
    wild_input.send_message(client_hello());
    pb::Envelope wild;
    wild.mutable_client_input()->set_view_yaw(1.0e9f);
    wild.mutable_client_input()->set_view_pitch(-500.0f);
    wild.mutable_client_input()->set_move_x(3.0e38f);
    wild_input.send_message(wild);

    expect_reason(nan_input, pb::DISCONNECT_REASON_INVALID_INPUT, "view_yaw");
    expect_reason(inf_input, pb::DISCONNECT_REASON_INVALID_INPUT, "move_y");
    expect_served(good);
    server.stop();
    // The clamped client was only told to go when the server shut down.
    expect_reason(wild_input, pb::DISCONNECT_REASON_SERVER_SHUTDOWN, "shut");
    EXPECT_GT(wild_input.snapshots(), 20u);
    EXPECT_EQ(server.stats().inputs_clamped, 1u);
}

TEST(ClientAbuse, OversizedFrameIsRefused) {
    RunningServer server(base_config());
    GoodClients good(server.port(), kGoodSeconds);
    RawClient before_hello(server.port()); // announces 1 MiB, the limit is 1 KiB
    std::array<std::uint8_t, 4> header{};
    protocol::write_frame_header(header.data(), 1024 * 1024);
    before_hello.send_bytes(header);

    RawClient after_hello(server.port()); // one byte over the limit, after a good hello
    after_hello.send_message(client_hello());
    std::vector<std::uint8_t> frame(4 + 1025, 0);
    protocol::write_frame_header(frame.data(), 1025);
    after_hello.send_bytes(frame);

    expect_reason(before_hello, pb::DISCONNECT_REASON_FRAME_TOO_LARGE, "1048576");
    expect_reason(after_hello, pb::DISCONNECT_REASON_FRAME_TOO_LARGE, "1025");
    expect_served(good);
}

class TokenAbuse : public ::testing::Test {
protected:
    server::ServerConfig config() const {
        auto c = base_config();
        c.token_key_file = key_file_.path();
        return c;
    }
    KeyFile key_file_;
};

TEST_F(TokenAbuse, BadTokensAreUnauthorized) {
    RunningServer server(config());
    GoodClients good(server.port(), kGoodSeconds, key_file_.key());

    RawClient none(server.port());
    none.send_message(client_hello());

    RawClient other_key(server.port());
    const auto forged = protocol::mint_connect_token(protocol::generate_token_key(),
                                                     {7, protocol::unix_now_s() + 60});
    other_key.send_message(client_hello(forged));

    RawClient tampered(server.port()); // a real token with its client id changed
    auto changed = protocol::mint_connect_token(key_file_.key(), {7, protocol::unix_now_s() + 60});
    changed[1] ^= 1;
    tampered.send_message(client_hello(changed));

    RawClient truncated(server.port());
    const std::vector<std::uint8_t> short_token(10, 1);
    truncated.send_message(client_hello(short_token));

    // A real token already in use by a good client (ids 1000..1002).
    RawClient duplicate(server.port());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    duplicate.send_message(client_hello(
        protocol::mint_connect_token(key_file_.key(), {1001, protocol::unix_now_s() + 60})));

    expect_reason(none, pb::DISCONNECT_REASON_UNAUTHORIZED, "no connect token");
    expect_reason(other_key, pb::DISCONNECT_REASON_UNAUTHORIZED, "signature");
    expect_reason(tampered, pb::DISCONNECT_REASON_UNAUTHORIZED, "signature");
    expect_reason(truncated, pb::DISCONNECT_REASON_UNAUTHORIZED, "10 bytes");
    expect_reason(duplicate, pb::DISCONNECT_REASON_UNAUTHORIZED, "already connected");
    EXPECT_FALSE(none.hello_received() || other_key.hello_received() || tampered.hello_received() ||
                 truncated.hello_received() || duplicate.hello_received());
    expect_served(good);
    server.stop();
    EXPECT_EQ(server.stats().disconnects.at("unauthorized"), 5u);
}

TEST_F(TokenAbuse, ExpiredTokenIsUnauthorized) {
    RunningServer server(config());
    GoodClients good(server.port(), kGoodSeconds, key_file_.key());
    RawClient expired(server.port());
    expired.send_message(client_hello(
        protocol::mint_connect_token(key_file_.key(), {9, protocol::unix_now_s() - 30})));
    expect_reason(expired, pb::DISCONNECT_REASON_UNAUTHORIZED, "expired");
    EXPECT_FALSE(expired.hello_received());

    RawClient valid(server.port()); // the same client id with a live token is welcome
    valid.send_message(client_hello(
        protocol::mint_connect_token(key_file_.key(), {9, protocol::unix_now_s() + 30})));
    expect_served(good);
    server.stop();
    expect_reason(valid, pb::DISCONNECT_REASON_SERVER_SHUTDOWN, "shut");
    EXPECT_TRUE(valid.hello_received());
}

} // namespace
} // namespace dsoc
