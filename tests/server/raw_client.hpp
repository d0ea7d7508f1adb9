#pragma once
// Test helpers for hostile-client tests: a raw TCP client that sends whatever the
// test wants, and a few well-behaved simulated clients running beside it, with the
// check that they were served all along.

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/framing.hpp"
#include "dsoc/simclient/load_report.hpp"
#include "dsoc/simclient/load_run.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <optional>
#include <span>
#include <thread>
#include <vector>

namespace dsoc::testing {

/// A blocking raw TCP connection to 127.0.0.1:port.
class RawClient {
public:
    /// `receive_buffer_bytes` > 0 shrinks SO_RCVBUF before connecting (a slow reader
    /// whose kernel buffer fills quickly); `source` (a loopback address, e.g. 127.0.0.2)
    /// connects from another address than 127.0.0.1.
    explicit RawClient(std::uint16_t port, int receive_buffer_bytes = 0,
                       const char* source = nullptr)
        : socket_(io_) {
        socket_.open(boost::asio::ip::tcp::v4());
        if (receive_buffer_bytes > 0) {
            socket_.set_option(boost::asio::socket_base::receive_buffer_size(receive_buffer_bytes));
        }
        if (source != nullptr) {
            socket_.bind({boost::asio::ip::make_address(source), 0});
        }
        socket_.connect({boost::asio::ip::make_address("127.0.0.1"), port});
    }

    /// Reads until the server's hello (true) or a Disconnect, the connection's end or
    /// `timeout` (false); `disconnect` gets the Disconnect, if one came first.
    bool read_until_hello(std::chrono::milliseconds timeout,
                          std::optional<protocol::pb::Disconnect>* disconnect = nullptr) {
        protocol::FrameDecoder decoder(16 * 1024 * 1024);
        std::array<std::uint8_t, 4096> buffer{};
        socket_.non_blocking(true);
        const auto until = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < until) {
            boost::system::error_code ec;
            const std::size_t n = socket_.read_some(boost::asio::buffer(buffer), ec);
            if (ec == boost::asio::error::would_block) {
                std::this_thread::sleep_for(std::chrono::milliseconds(2));
                continue;
            }
            if (ec) {
                break;
            }
            decoder.feed(std::span<const std::uint8_t>(buffer.data(), n));
            std::span<const std::uint8_t> payload;
            while (decoder.next(payload) == protocol::FrameDecoder::Status::frame) {
                protocol::pb::Envelope message;
                if (protocol::decode_payload(payload, message) != protocol::DecodeError::none) {
                    continue;
                }
                if (message.has_server_hello()) {
                    socket_.non_blocking(false);
                    return true;
                }
                if (message.has_disconnect()) {
                    if (disconnect != nullptr) {
                        *disconnect = message.disconnect();
                    }
                    socket_.non_blocking(false);
                    return false;
                }
            }
        }
        socket_.non_blocking(false);
        return false;
    }

    void send_bytes(std::span<const std::uint8_t> bytes) {
        boost::asio::write(socket_, boost::asio::buffer(bytes.data(), bytes.size()));
    }

    void send_message(const protocol::pb::Envelope& message) {
        std::vector<std::uint8_t> frame;
        protocol::encode_frame(message, frame);
        send_bytes(frame);
    }

    /// Reads until the server closes the connection; returns its Disconnect, if one
    /// arrived, and counts the snapshots seen on the way. A slow reader passes
    /// `chunk` < 4096 bytes per read and a `pause` between reads.
    std::optional<protocol::pb::Disconnect>
    read_until_closed(std::size_t chunk = 4096,
                      std::chrono::milliseconds pause = std::chrono::milliseconds(0)) {
        protocol::FrameDecoder decoder(16 * 1024 * 1024);
        std::optional<protocol::pb::Disconnect> disconnect;
        std::array<std::uint8_t, 4096> buffer{};
        for (;;) {
            boost::system::error_code ec;
            const std::size_t n = socket_.read_some(
                boost::asio::buffer(buffer.data(), std::min(chunk, buffer.size())), ec);
            if (ec) {
                trailing_bytes_ = decoder.buffered_bytes();
                break;
            }
            if (pause.count() > 0) {
                std::this_thread::sleep_for(pause);
            }
            decoder.feed(std::span<const std::uint8_t>(buffer.data(), n));
            std::span<const std::uint8_t> payload;
            while (decoder.next(payload) == protocol::FrameDecoder::Status::frame) {
                protocol::pb::Envelope message;
                if (protocol::decode_payload(payload, message) != protocol::DecodeError::none) {
                    ++undecodable_frames_;
                    continue;
                }
                if (message.has_disconnect()) {
                    disconnect = message.disconnect();
                } else if (message.has_snapshot()) {
                    ++snapshots_;
                } else if (message.has_server_hello()) {
                    hello_received_ = true;
                    hello_ = message.server_hello();
                }
            }
        }
        return disconnect;
    }

    [[nodiscard]] std::uint64_t snapshots() const { return snapshots_; }
    /// Frames whose payload did not decode as an envelope (bytes lost or mixed up).
    [[nodiscard]] std::uint64_t undecodable_frames() const { return undecodable_frames_; }
    [[nodiscard]] bool hello_received() const { return hello_received_; }
    /// The server's hello, once hello_received().
    [[nodiscard]] const protocol::pb::ServerHello& hello() const { return hello_; }
    /// Bytes of an unfinished frame when the connection ended (a cut-off frame).
    [[nodiscard]] std::size_t trailing_bytes() const { return trailing_bytes_; }

private:
    boost::asio::io_context io_;
    boost::asio::ip::tcp::socket socket_;
    std::uint64_t snapshots_ = 0;
    std::uint64_t undecodable_frames_ = 0;
    bool hello_received_ = false;
    protocol::pb::ServerHello hello_;
    std::size_t trailing_bytes_ = 0;
};

/// A ClientHello of the current protocol, optionally with a connect token.
inline protocol::pb::Envelope client_hello(std::span<const std::uint8_t> token = {}) {
    protocol::pb::Envelope m;
    m.mutable_client_hello()->set_protocol_version(protocol::kProtocolVersion);
    m.mutable_client_hello()->set_name("raw");
    if (!token.empty()) {
        m.mutable_client_hello()->set_connect_token(token.data(), token.size());
    }
    return m;
}

/// Well-behaved dsoc-simclient clients on a thread of their own, from construction until
/// finish(), while the test does what it wants to the server beside them.
class GoodClients {
public:
    /// `clients` TCP clients, all connecting at once, for `seconds`; with `key`, each
    /// mints a token for client id 1000 + index.
    GoodClients(std::uint16_t port, double seconds,
                std::optional<protocol::TokenKey> key = std::nullopt, int clients = 3)
        : GoodClients(tcp_config(port, seconds, key, clients)) {}
    /// The clients `config` describes (its progress lines are turned off).
    explicit GoodClients(simclient::LoadConfig config) : config_(std::move(config)) {
        config_.progress = false;
        run_ = std::make_unique<simclient::LoadRun>(io_, config_);
        run_->start();
        thread_ = std::thread([this] { io_.run(); });
    }
    ~GoodClients() { finish(); }
    GoodClients(const GoodClients&) = delete;
    GoodClients& operator=(const GoodClients&) = delete;

    /// Waits for the end of the run.
    simclient::LoadReport finish() {
        if (thread_.joinable()) {
            thread_.join();
        }
        return run_->report();
    }

    [[nodiscard]] const simclient::LoadRun& run() const { return *run_; }
    [[nodiscard]] double seconds() const { return config_.duration_s; }

private:
    static simclient::LoadConfig tcp_config(std::uint16_t port, double seconds,
                                            std::optional<protocol::TokenKey> key, int clients) {
        simclient::LoadConfig c;
        c.transport = simclient::LoadConfig::Transport::tcp;
        c.port = port;
        c.clients = clients;
        c.duration_s = seconds;
        c.ramp_up_s = 0.0;
        c.token_key = key;
        c.client_id_base = 1000;
        return c;
    }

    simclient::LoadConfig config_;
    boost::asio::io_context io_;
    std::unique_ptr<simclient::LoadRun> run_;
    std::thread thread_;
};

/// Waits for the end of `good`'s run and checks that its clients were served all along:
/// all connected, no protocol error, no unexpected disconnect, the 99th percentile of
/// the time between snapshots under `max_interarrival_p99_ms`, and each client got at
/// least 70% of the snapshots 30 Hz (the default tick rate) makes over the run.
inline void expect_served(GoodClients& good, double max_interarrival_p99_ms = 150.0) {
    const auto report = good.finish();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_LT(report.snapshot_interarrival_ms.p99, max_interarrival_p99_ms)
        << simclient::format_summary(report);
    const double expected = good.seconds() * 30.0;
    for (const auto& client : good.run().clients()) {
        EXPECT_GE(static_cast<double>(client->stats().snapshots), 0.7 * expected);
    }
}

} // namespace dsoc::testing
