// Hostile and broken clients are disconnected with a reason while well-behaved
// clients keep receiving snapshots at the tick rate.

#include "server_fixture.hpp"

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/framing.hpp"
#include "dsoc/simclient/load_run.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>

#include <gtest/gtest.h>

#include <optional>

namespace dsoc {
namespace {

namespace asio = boost::asio;
namespace pb = protocol::pb;

/// A raw TCP connection that sends whatever the test wants and collects what the
/// server says until it closes the connection.
class RawClient {
public:
    explicit RawClient(std::uint16_t port) : socket_(io_) {
        socket_.connect({asio::ip::make_address("127.0.0.1"), port});
    }

    void send_bytes(const std::vector<std::uint8_t>& bytes) {
        asio::write(socket_, asio::buffer(bytes));
    }

    void send_message(const pb::Envelope& message) {
        std::vector<std::uint8_t> frame;
        protocol::encode_frame(message, frame);
        send_bytes(frame);
    }

    /// Reads until EOF and returns the Disconnect the server sent, if any.
    std::optional<pb::Disconnect> read_until_closed() {
        protocol::FrameDecoder decoder(16 * 1024 * 1024);
        std::optional<pb::Disconnect> disconnect;
        std::array<std::uint8_t, 4096> buffer{};
        for (;;) {
            boost::system::error_code ec;
            const std::size_t n = socket_.read_some(asio::buffer(buffer), ec);
            if (ec) {
                break;
            }
            decoder.feed(std::span<const std::uint8_t>(buffer.data(), n));
            std::span<const std::uint8_t> payload;
            while (decoder.next(payload) == protocol::FrameDecoder::Status::frame) {
                pb::Envelope message;
                if (protocol::decode_payload(payload, message) == protocol::DecodeError::none &&
                    message.has_disconnect()) {
                    disconnect = message.disconnect();
                }
            }
        }
        return disconnect;
    }

private:
    asio::io_context io_;
    asio::ip::tcp::socket socket_;
};

pb::Envelope hello(std::uint32_t version = protocol::kProtocolVersion) {
    pb::Envelope m;
    m.mutable_client_hello()->set_protocol_version(version);
    m.mutable_client_hello()->set_name("raw");
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

    const simclient::LoadConfig lc = testing::load_config(server, 4, 2.5, 0.0);
    asio::io_context io;
    simclient::LoadRun run(io, lc);
    run.start();
    std::thread good_clients([&] { io.run(); });
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
    old_version.send_message(hello(99));

    // 5. Valid hello, then a NaN in its input.
    RawClient nan_input(server.port());
    nan_input.send_message(hello());
    pb::Envelope input;
    input.mutable_client_input()->set_view_yaw(std::nanf(""));
    nan_input.send_message(input);

    // 6. Sends a server-only message.
    RawClient impostor(server.port());
    impostor.send_message(hello());
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

    good_clients.join();
    server.stop();

    const auto report = run.report();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    // The well-behaved clients kept getting snapshots at the tick rate throughout.
    EXPECT_LT(report.snapshot_interarrival_ms.p99, 100.0) << simclient::format_summary(report);
    for (const auto& client : run.clients()) {
        EXPECT_GE(client->stats().snapshots, 55u); // ~2.5 s at 30 Hz = 75
    }
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
    first.send_message(hello());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    RawClient second(server.port());
    const auto d = second.read_until_closed();
    ASSERT_TRUE(d.has_value());
    EXPECT_EQ(d->reason(), pb::DISCONNECT_REASON_SERVER_FULL);
}

} // namespace
} // namespace dsoc
