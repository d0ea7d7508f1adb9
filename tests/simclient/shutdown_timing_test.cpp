// A server shutdown fails the run before the scenario's end and is the expected end
// after it. A scripted server on loopback (no game): it answers the hello, then announces
// its shutdown at a chosen time, ignoring the client's goodbye so that the announcement
// can come after the run's end.

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/quantization.hpp"
#include "dsoc/simclient/load_run.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <gtest/gtest.h>

namespace dsoc::simclient {
namespace {

namespace asio = boost::asio;
namespace pb = protocol::pb;

/// Accepts one client, sends a server hello at once and Disconnect(server_shutdown)
/// `shutdown_after` later, then closes.
class ScriptedServer {
public:
    ScriptedServer(asio::io_context& io, std::chrono::milliseconds shutdown_after)
        : acceptor_(io, {asio::ip::make_address("127.0.0.1"), 0}), socket_(io), timer_(io),
          shutdown_after_(shutdown_after) {
        acceptor_.async_accept(socket_, [this](const boost::system::error_code& ec) {
            if (!ec) {
                on_accepted();
            }
        });
    }
    [[nodiscard]] std::uint16_t port() const { return acceptor_.local_endpoint().port(); }

private:
    void on_accepted() {
        pb::Envelope hello;
        auto& h = *hello.mutable_server_hello();
        h.set_protocol_version(protocol::kProtocolVersion);
        h.set_client_id(1);
        h.set_entity_id(1);
        h.set_tick_rate(30);
        protocol::to_message(protocol::QuantizationSettings{}, *h.mutable_quantization());
        protocol::encode_frame(hello, out_);
        asio::write(socket_, asio::buffer(out_));
        drain();
        timer_.expires_after(shutdown_after_);
        timer_.async_wait([this](const boost::system::error_code& ec) {
            if (ec) {
                return;
            }
            pb::Envelope bye;
            bye.mutable_disconnect()->set_reason(pb::DISCONNECT_REASON_SERVER_SHUTDOWN);
            bye.mutable_disconnect()->set_text("server shutting down");
            out_.clear();
            protocol::encode_frame(bye, out_);
            boost::system::error_code ignored;
            asio::write(socket_, asio::buffer(out_), ignored);
            socket_.close(ignored);
        });
    }
    void drain() { // reads and ignores what the client sends (its goodbye included)
        socket_.async_read_some(asio::buffer(in_),
                                [this](const boost::system::error_code& ec, std::size_t) {
                                    if (!ec) {
                                        drain();
                                    }
                                });
    }

    asio::ip::tcp::acceptor acceptor_;
    asio::ip::tcp::socket socket_;
    asio::steady_timer timer_;
    std::chrono::milliseconds shutdown_after_;
    std::vector<std::uint8_t> out_;
    std::array<std::uint8_t, 4096> in_{};
};

LoadReport run_against(std::chrono::milliseconds shutdown_after, double duration_s) {
    asio::io_context io;
    ScriptedServer server(io, shutdown_after);
    LoadConfig config;
    config.transport = LoadConfig::Transport::tcp; // the scripted server speaks TCP
    config.port = server.port();
    config.clients = 1;
    config.duration_s = duration_s;
    config.ramp_up_s = 0.0;
    config.progress = false;
    LoadRun run(io, config);
    run.start();
    io.run();
    return run.report();
}

TEST(ServerShutdown, BeforeTheScenariosEndFailsTheRunAndStopsIt) {
    const auto start = std::chrono::steady_clock::now();
    const LoadReport r = run_against(std::chrono::milliseconds(300), 5.0);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(4));
    EXPECT_EQ(r.connected, 1);
    EXPECT_EQ(r.failures_by_reason, (std::map<std::string, std::uint64_t>{{"server_shutdown", 1}}));
    EXPECT_NE(r.stopped_early.find("the server shut down at 0.3 s, before the scenario's end at "
                                   "5.0 s"),
              std::string::npos)
        << r.stopped_early;
    EXPECT_EQ(r.unexpected_disconnects, 0); // the server said why
    EXPECT_FALSE(r.passed());
}

TEST(ServerShutdown, AfterTheScenariosEndIsTheExpectedEnd) {
    // The run ends at 0.5 s and says goodbye; this server ignores it and announces its
    // shutdown at 0.8 s, within the client's grace for the server to close.
    const LoadReport r = run_against(std::chrono::milliseconds(800), 0.5);
    EXPECT_EQ(r.connected, 1);
    EXPECT_EQ(r.disconnect_reasons, (std::map<std::string, std::uint64_t>{{"server_shutdown", 1}}));
    EXPECT_EQ(r.failures, 0u) << format_summary(r);
    EXPECT_TRUE(r.stopped_early.empty()) << r.stopped_early;
}

} // namespace
} // namespace dsoc::simclient
