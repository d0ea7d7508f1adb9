// The server keeps serving I/O while a tick's parallel phase (every client's interest
// evaluation and snapshot) runs on the worker pool: a ping is answered, a new
// client's hello is answered and /metrics answers, each within a fraction of the
// phase's length, through real sockets against a real server on a real map. The
// probe also sends inputs, and the hello connections leave at once, so joins, inputs
// and leaves all arrive while phases run (the sanitizer builds check that the I/O
// thread then writes nothing the jobs read).
//
// The server is made to spend nearly all its time in the parallel phase: oa_dm4 with
// the dsoc policy, one pool thread and 250 joined clients that never read (their
// culling still runs every tick), at a tick rate the phase cannot keep up with, so
// ticks run back to back. A server whose I/O thread is blocked during the phase
// answers a request arriving at a random time only when the phase ends: the median
// wait is then about half a phase (measured: the test fails that way on the server
// before I/O and the pool were separated). The bound compares medians with the
// phase length measured by the server itself in the same window, so a slow or busy
// machine makes both longer together rather than making the test flaky.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/framing.hpp"
#include "dsoc/server/metrics_endpoint.hpp"
#include "dsoc/server/server.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <future>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <poll.h>

namespace dsoc {
namespace {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using Clock = std::chrono::steady_clock;

pb::Envelope client_hello() {
    pb::Envelope m;
    m.mutable_client_hello()->set_protocol_version(protocol::kProtocolVersion);
    m.mutable_client_hello()->set_name("io-test");
    return m;
}

/// A server and its metrics endpoint on one io_context, run on one thread by an
/// IoLoop with the config's gather (as dsoc-server runs them).
class ServerWithMetrics {
public:
    ServerWithMetrics(server::ServerConfig config, std::shared_ptr<const maps::Map> map)
        : loop_(io_, std::chrono::microseconds(config.io_gather_us)),
          server_(io_, std::move(config), std::move(map)),
          metrics_(io_, [this] { return server_.render_metrics(); }) {
        server_.set_io_loop(&loop_);
        port_ = server_.start();
        metrics_port_ = metrics_.start("127.0.0.1", 0);
        thread_ = std::thread([this] { loop_.run(); });
    }
    ~ServerWithMetrics() { stop(); }
    ServerWithMetrics(const ServerWithMetrics&) = delete;
    ServerWithMetrics& operator=(const ServerWithMetrics&) = delete;

    void stop() {
        if (!thread_.joinable()) {
            return;
        }
        asio::post(io_, [this] {
            metrics_.stop();
            server_.shutdown();
        });
        thread_.join();
    }

    /// Parallel phases so far and their total wall time in seconds (the server's
    /// culling_duration: begin_tick plus the per-client work on the pool), read on the
    /// server's thread.
    std::pair<std::uint64_t, double> phases() {
        std::promise<std::pair<std::uint64_t, double>> result;
        asio::post(io_, [&] {
            result.set_value(
                {server_.stats().culling_duration.count(), server_.stats().culling_duration.sum()});
        });
        return result.get_future().get();
    }

    [[nodiscard]] std::uint16_t port() const { return port_; }
    [[nodiscard]] std::uint16_t metrics_port() const { return metrics_port_; }

private:
    asio::io_context io_;
    server::IoLoop loop_; // before the server, which wakes it until it is destroyed
    server::Server server_;
    server::MetricsEndpoint metrics_;
    std::uint16_t port_ = 0;
    std::uint16_t metrics_port_ = 0;
    std::thread thread_;
};

/// A blocking TCP connection with read deadlines, for timing one request at a time.
class TimedConnection {
public:
    explicit TimedConnection(std::uint16_t port) : socket_(io_) {
        socket_.connect({asio::ip::make_address("127.0.0.1"), port});
        socket_.set_option(asio::ip::tcp::no_delay(true));
    }

    void send(std::string_view bytes) {
        asio::write(socket_, asio::buffer(bytes.data(), bytes.size()));
    }
    void send(const pb::Envelope& message) {
        std::vector<std::uint8_t> frame;
        protocol::encode_frame(message, frame);
        asio::write(socket_, asio::buffer(frame));
    }

    /// Reads what has arrived, waiting up to `timeout`; empty on timeout, closed or error.
    std::span<const std::uint8_t> read_some(std::chrono::milliseconds timeout) {
        pollfd fd{socket_.native_handle(), POLLIN, 0};
        if (::poll(&fd, 1, static_cast<int>(timeout.count())) <= 0) {
            return {};
        }
        boost::system::error_code ec;
        const std::size_t n = socket_.read_some(asio::buffer(buffer_), ec);
        return ec ? std::span<const std::uint8_t>{} : std::span(buffer_.data(), n);
    }

    /// Reads frames until `wanted` accepts one; false when none came within `timeout`.
    template <class Wanted>
    bool read_until(Wanted wanted, std::chrono::milliseconds timeout) {
        const auto deadline = Clock::now() + timeout;
        for (;;) {
            std::span<const std::uint8_t> payload;
            while (decoder_.next(payload) == protocol::FrameDecoder::Status::frame) {
                pb::Envelope message;
                if (protocol::decode_payload(payload, message) == protocol::DecodeError::none &&
                    wanted(message)) {
                    return true;
                }
            }
            const auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
            if (left.count() <= 0) {
                return false;
            }
            const auto bytes = read_some(left);
            if (bytes.empty()) {
                return false;
            }
            decoder_.feed(bytes);
        }
    }

private:
    asio::io_context io_;
    asio::ip::tcp::socket socket_;
    std::array<std::uint8_t, 64 * 1024> buffer_{};
    protocol::FrameDecoder decoder_{16 * 1024 * 1024};
};

constexpr auto kReplyTimeout = std::chrono::milliseconds(20'000);

double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// Milliseconds from sending a ping to its pong, on a joined client.
double ping_ms(TimedConnection& client, std::uint64_t nonce) {
    pb::Envelope ping;
    ping.mutable_ping()->set_nonce(nonce);
    const auto sent = Clock::now();
    client.send(ping);
    const bool answered = client.read_until(
        [&](const pb::Envelope& m) { return m.has_pong() && m.pong().nonce() == nonce; },
        kReplyTimeout);
    EXPECT_TRUE(answered) << "no pong for ping " << nonce;
    return ms_since(sent);
}

/// Milliseconds from a new connection's hello to its ServerHello.
double hello_ms(std::uint16_t port) {
    TimedConnection client(port);
    const auto sent = Clock::now();
    client.send(client_hello());
    const bool answered = client.read_until(
        [](const pb::Envelope& m) { return m.has_server_hello(); }, kReplyTimeout);
    EXPECT_TRUE(answered) << "no server_hello";
    return ms_since(sent);
}

/// Milliseconds from connecting to /metrics to the end of its answer.
double metrics_ms(std::uint16_t port) {
    const auto sent = Clock::now();
    TimedConnection scrape(port);
    scrape.send("GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    std::string answer;
    for (auto bytes = scrape.read_some(kReplyTimeout); !bytes.empty();
         bytes = scrape.read_some(kReplyTimeout)) {
        answer.append(bytes.begin(), bytes.end());
    }
    EXPECT_NE(answer.find("dsoc_ticks_total"), std::string::npos) << answer.substr(0, 200);
    return ms_since(sent);
}

TEST(IoDuringTick, PingsHellosAndMetricsAreAnsweredWhileTheParallelPhaseRuns) {
    auto loaded = maps::load_map("oa_dm4", maps::MapSearch::from_environment());
    if (!loaded) {
        GTEST_SKIP() << "OpenArena maps not installed (scripts/setup installs openarena-081-maps)";
    }
    constexpr int kSilentClients = 250;
    server::ServerConfig config;
    config.port = 0;
    config.insecure = true;
    config.map = "oa_dm4";
    config.policy = interest::PolicyKind::dsoc;
    config.baked_stage = false;  // the exact stages: long phases, no bake
    config.culling_budget = 0.0; // and no fail-open to shorten them
    config.bots = 300;
    config.threads = 1;    // one pool thread: long phases on any machine
    config.tick_rate = 60; // more than the phase allows: ticks run back to back
    config.max_clients = 500;
    config.slow_client_timeout_ms = 60000; // the silent clients stay
    config.max_inputs_per_second = 5000;   // the probe pings often
    ServerWithMetrics server(config, std::make_shared<const maps::Map>(std::move(loaded).value()));

    // Joined clients that never read: their culling runs every tick all the same.
    std::vector<std::unique_ptr<TimedConnection>> silent;
    for (int i = 0; i < kSilentClients; ++i) {
        silent.push_back(std::make_unique<TimedConnection>(server.port()));
        silent.back()->send(client_hello());
    }
    TimedConnection probe(server.port());
    probe.send(client_hello());
    ASSERT_TRUE(probe.read_until([](const pb::Envelope& m) { return m.has_server_hello(); },
                                 kReplyTimeout));
    // Every hello before the probe's has been answered; the next tick start spawns
    // them, so two more phases and every silent client is being culled.
    const auto joined_at = server.phases().first;
    while (server.phases().first < joined_at + 2) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }

    std::mt19937 rng(7);
    std::uniform_int_distribution<int> pause_ms(0, 15); // requests at random points of a tick
    std::vector<double> pings;
    std::vector<double> hellos;
    std::vector<double> scrapes;
    const auto [phases_before, phase_s_before] = server.phases();
    // At least 3 s, 12 rounds and 3 whole phases (a sanitizer build's phases take
    // seconds), at most 120 s.
    const auto start = Clock::now();
    const auto enough = [&](std::uint64_t rounds) {
        const auto elapsed = Clock::now() - start;
        return elapsed > std::chrono::seconds(120) ||
               (elapsed >= std::chrono::seconds(3) && rounds >= 12 &&
                server.phases().first >= phases_before + 3);
    };
    for (std::uint64_t round = 1; !enough(round - 1); ++round) {
        pb::Envelope input; // read during the phase, handed to the world at the next tick
        input.mutable_client_input()->set_tick(round);
        input.mutable_client_input()->set_move_x(round % 2 == 0 ? 1.0f : -1.0f);
        input.mutable_client_input()->set_view_yaw(static_cast<float>(round % 360) - 180.0f);
        probe.send(input);
        pings.push_back(ping_ms(probe, round));
        std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms(rng)));
        if (round % 3 == 0) {
            hellos.push_back(hello_ms(server.port()));
            std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms(rng)));
            scrapes.push_back(metrics_ms(server.metrics_port()));
            std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms(rng)));
        }
    }
    const auto [phases_after, phase_s_after] = server.phases();
    server.stop();

    ASSERT_GT(phases_after, phases_before);
    const double phase_ms = 1000.0 * (phase_s_after - phase_s_before) /
                            static_cast<double>(phases_after - phases_before);
    const std::string figures =
        "mean parallel phase " + std::to_string(phase_ms) + " ms over " +
        std::to_string(phases_after - phases_before) + " ticks; medians: ping " +
        std::to_string(median(pings)) + " ms (" + std::to_string(pings.size()) + "), hello " +
        std::to_string(median(hellos)) + " ms (" + std::to_string(hellos.size()) + "), metrics " +
        std::to_string(median(scrapes)) + " ms (" + std::to_string(scrapes.size()) + ")";
    // The phase must be long enough to tell "answered during it" from "after it".
    ASSERT_GE(phase_ms, 5.0) << "the load is too light to observe anything: " << figures;
    EXPECT_LT(median(pings), phase_ms / 4) << figures;
    EXPECT_LT(median(hellos), phase_ms / 4) << figures;
    EXPECT_LT(median(scrapes), phase_ms / 4) << figures;
    std::printf("%s\n", figures.c_str());
}

} // namespace
} // namespace dsoc
