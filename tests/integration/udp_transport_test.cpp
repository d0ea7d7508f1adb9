// The UDP transport end to end: simulated clients over real UDP sockets to a real
// server get their snapshots, audits and own entity, with and without emulated loss;
// hostile datagrams are dropped and counted by reason, never answered with more bytes
// than they carried, while the honest clients keep their snapshots; a silent client is
// timed out with a reason.

#include "server_fixture.hpp"

#include "dsoc/simclient/load_run.hpp"

#include "dsoc/protocol/challenge_cookie.hpp"
#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/protocol/datagram.hpp"
#include "dsoc/server/snapshot_pacer.hpp"
#include "server/raw_client.hpp"

#include <boost/asio/ip/udp.hpp>

#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <optional>
#include <thread>

namespace dsoc {
namespace {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using protocol::DatagramKind;
using server::UdpDrop;

/// A blocking raw UDP socket towards the server, sending whatever the test wants.
class RawUdp {
public:
    explicit RawUdp(std::uint16_t port)
        : socket_(io_), server_(asio::ip::make_address("127.0.0.1"), port) {
        socket_.open(asio::ip::udp::v4());
        socket_.bind({asio::ip::make_address("127.0.0.1"), 0});
    }

    void send(std::span<const std::uint8_t> bytes) {
        socket_.send_to(asio::buffer(bytes.data(), bytes.size()), server_);
    }

    /// The next datagram from the server within `timeout`, or nothing.
    std::optional<std::vector<std::uint8_t>>
    receive(std::chrono::milliseconds timeout = std::chrono::milliseconds(1000)) {
        const auto until = std::chrono::steady_clock::now() + timeout;
        std::array<std::uint8_t, 2048> buffer{};
        socket_.non_blocking(true);
        while (std::chrono::steady_clock::now() < until) {
            boost::system::error_code ec;
            asio::ip::udp::endpoint from;
            const std::size_t n = socket_.receive_from(asio::buffer(buffer), from, 0, ec);
            if (!ec) {
                return std::vector<std::uint8_t>(buffer.begin(), buffer.begin() + n);
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        return std::nullopt;
    }

    /// The next datagram of `kind` within `timeout` (others are skipped).
    std::optional<std::vector<std::uint8_t>> receive_kind(DatagramKind kind,
                                                          std::chrono::milliseconds timeout) {
        const auto until = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < until) {
            auto d = receive(std::chrono::duration_cast<std::chrono::milliseconds>(
                until - std::chrono::steady_clock::now()));
            protocol::DatagramHeader h;
            std::span<const std::uint8_t> body;
            if (d && protocol::read_datagram(*d, h, body) == protocol::DatagramError::none &&
                h.kind == kind) {
                return d;
            }
        }
        return std::nullopt;
    }

    /// Request, challenge, response, accepted: returns the session id (0 on failure);
    /// `reply` gets the accepted datagram's envelope (a ServerHello or a Disconnect).
    std::uint64_t handshake(std::uint64_t nonce, const pb::Envelope& hello, pb::Envelope& reply) {
        std::vector<std::uint8_t> request;
        EXPECT_TRUE(protocol::write_request(nonce, hello, request));
        send(request);
        const auto challenge = receive_kind(DatagramKind::challenge, std::chrono::seconds(2));
        if (!challenge) {
            return 0;
        }
        challenge_bytes = challenge->size();
        protocol::DatagramHeader h;
        std::span<const std::uint8_t> cookie;
        EXPECT_EQ(protocol::read_datagram(*challenge, h, cookie), protocol::DatagramError::none);
        EXPECT_TRUE(protocol::write_response(nonce, cookie, hello, response));
        send(response);
        const auto got = receive_kind(DatagramKind::accepted, std::chrono::seconds(2));
        if (!got) {
            return 0;
        }
        accepted = *got;
        std::span<const std::uint8_t> body;
        EXPECT_EQ(protocol::read_datagram(accepted, h, body), protocol::DatagramError::none);
        std::uint64_t session = 0;
        std::span<const std::uint8_t> envelope;
        EXPECT_EQ(protocol::read_accepted_body(body, session, envelope),
                  protocol::DatagramError::none);
        EXPECT_EQ(protocol::decode_payload(envelope, reply), protocol::DecodeError::none);
        return session;
    }

    /// Sends the request of `nonce` with `hello`.
    void send_request(std::uint64_t nonce, const pb::Envelope& hello) {
        std::vector<std::uint8_t> request;
        EXPECT_TRUE(protocol::write_request(nonce, hello, request));
        send(request);
    }

    /// How many datagrams of `kind` arrive until none has for `quiet`.
    int count_kind(DatagramKind kind, std::chrono::milliseconds quiet) {
        int count = 0;
        while (receive_kind(kind, quiet)) {
            ++count;
        }
        return count;
    }

    /// The same with an insecure hello; the session id of a ServerHello (0 otherwise).
    std::uint64_t handshake(std::uint64_t nonce) {
        pb::Envelope reply;
        const std::uint64_t session = handshake(nonce, plain_hello(), reply);
        EXPECT_TRUE(reply.has_server_hello());
        return reply.has_server_hello() ? session : 0;
    }

    static pb::Envelope plain_hello() {
        pb::Envelope hello;
        hello.mutable_client_hello()->set_protocol_version(protocol::kProtocolVersion);
        hello.mutable_client_hello()->set_name("raw-udp");
        return hello;
    }

    std::vector<std::uint8_t> response; ///< the last handshake's
    std::vector<std::uint8_t> accepted; ///< the last handshake's
    std::size_t challenge_bytes = 0;

private:
    asio::io_context io_;
    asio::ip::udp::socket socket_;
    asio::ip::udp::endpoint server_;
};

std::vector<std::uint8_t> input_datagram(std::uint64_t session, std::uint32_t sequence) {
    pb::ClientInput input;
    input.set_tick(sequence);
    input.set_move_x(1.0f);
    std::vector<std::uint8_t> out;
    EXPECT_TRUE(protocol::write_input({DatagramKind::input, session, sequence}, 0,
                                      std::span(&input, 1), out));
    return out;
}

simclient::LoadConfig udp_load(const testing::RunningServer& server, int clients,
                               double duration_s) {
    simclient::LoadConfig lc = testing::load_config(server, clients, duration_s, 0.2);
    lc.transport = simclient::LoadConfig::Transport::udp;
    lc.audit_every_ticks = 5;
    return lc;
}

std::uint64_t drops(const testing::RunningServer& server, UdpDrop reason) {
    return server.udp_endpoint()->drops()[static_cast<std::size_t>(reason)];
}

server::ServerConfig udp_config() {
    server::ServerConfig c;
    c.bots = 30;
    return c;
}

TEST(UdpTransport, ClientsGetSnapshotsAuditsAndTheirOwnEntity) {
    testing::RunningServer server(udp_config());
    const simclient::LoadReport report = testing::run_load(udp_load(server, 6, 3.0));
    // A UDP client's goodbye is one datagram, not the end of a stream the client waits
    // to see closed: give the server a moment to read them before it shuts down.
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    server.stop();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_EQ(report.connected, 6);
    EXPECT_GE(report.snapshots, 6u * 70u); // ~2.8 s at 30 Hz each
    EXPECT_GT(report.audited_poses, 0u);
    EXPECT_LE(report.max_audit_error, 0.5 + 1e-3);
    EXPECT_LT(report.snapshot_interarrival_ms.p99, 100.0);
    // The same gaps as the sockets received them: a tick apart, every snapshot after a
    // client's first, each handled after it arrived.
    EXPECT_EQ(report.snapshot_socket_interarrival_ms.count, report.snapshot_interarrival_ms.count);
    EXPECT_NEAR(report.snapshot_socket_interarrival_ms.p50, 1000.0 / 30.0, 8.0);
    EXPECT_EQ(report.handling_lag_ms.count, report.snapshots);
    EXPECT_GE(report.handling_lag_ms.p50, 0.0);
    EXPECT_LT(report.handling_lag_ms.p50, report.snapshot_socket_interarrival_ms.p50);
    EXPECT_EQ(server.stats().disconnects.at("client_quit"), 6u);
    EXPECT_GT(server.stats().snapshots_sent, 0u);
    // Acknowledgements carried the run: after each client's first snapshot, every one
    // was coded against a frame it acknowledged, a tick or two old on loopback.
    const auto& stats = server.stats();
    EXPECT_EQ(stats.acked_snapshots_against_baseline + stats.acked_snapshots_whole,
              stats.snapshots_sent);
    EXPECT_GT(stats.acked_snapshots_against_baseline, 4 * stats.acked_snapshots_whole);
    EXPECT_LT(static_cast<double>(stats.acked_baseline_age_ticks),
              4.0 * static_cast<double>(stats.acked_snapshots_against_baseline));
    EXPECT_NE(server.render_metrics().find("dsoc_udp_snapshots_total{coded=\"whole\"}"),
              std::string::npos);
    for (std::size_t r = 0; r < server::kUdpDropReasons; ++r) {
        // Each client says goodbye twice (nothing acknowledges it): the second one finds
        // its session closed.
        const std::uint64_t expected = static_cast<UdpDrop>(r) == UdpDrop::closed_session ? 6 : 0;
        EXPECT_EQ(server.udp_endpoint()->drops()[r], expected)
            << server::udp_drop_name(static_cast<UdpDrop>(r));
    }
}

TEST(UdpTransport, ClientsThatDiscardSnapshotsStillAcknowledgeEachSoTheServerCodesDeltas) {
    testing::RunningServer server(udp_config());
    simclient::LoadConfig lc = udp_load(server, 6, 3.0);
    lc.check_every = 3; // 0 (the group's first), 1 and 5 decode and check; 2, 3, 4 discard
    boost::asio::io_context io;
    simclient::LoadRun run(io, lc);
    run.start();
    io.run();
    std::this_thread::sleep_for(std::chrono::milliseconds(300)); // the goodbyes, as above
    server.stop();
    const simclient::LoadReport report = run.report();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_EQ(report.connected, 6);
    EXPECT_EQ(report.missing_own_entity, 0); // a discarding client finds it among the enters
    EXPECT_GT(report.audited_poses, 0u);     // the checking clients' audits
    std::uint64_t checked = 0;
    int checking = 0;
    for (const auto& client : run.clients()) {
        const simclient::ClientStats& s = client->stats();
        const int index = client->setup().index;
        EXPECT_EQ(s.checks_snapshots, index == 0 || simclient::picked_to_check(index, 3))
            << client->name();
        checking += s.checks_snapshots ? 1 : 0;
        EXPECT_GE(s.snapshots, 50u) << client->name(); // ~2.8 s at 30 Hz
        EXPECT_TRUE(s.saw_own_entity) << client->name();
        if (s.checks_snapshots) {
            checked += s.snapshots;
            EXPECT_GT(s.known_samples.count(), 0u) << client->name();
        } else {
            EXPECT_EQ(s.known_samples.count(), 0u) << client->name(); // never decoded
            EXPECT_EQ(client->known(), 0u) << client->name();
        }
    }
    EXPECT_EQ(report.checked_snapshots, checked);
    ASSERT_GE(checking, 1);
    ASSERT_LE(checking, 4); // so that at least two discard
    // The discarding clients acknowledged what they received, as the checking ones: the
    // server coded their snapshots against frames they acknowledged, not whole (were a
    // discarding client's acknowledgement missing, a third or more of the snapshots would
    // be), a tick or two old on loopback (a stale acknowledgement makes them older).
    const auto& stats = server.stats();
    EXPECT_GE(stats.snapshots_sent, report.snapshots);
    EXPECT_EQ(stats.acked_snapshots_against_baseline + stats.acked_snapshots_whole,
              stats.snapshots_sent);
    EXPECT_GT(stats.acked_snapshots_against_baseline, 4 * stats.acked_snapshots_whole);
    EXPECT_LT(static_cast<double>(stats.acked_baseline_age_ticks),
              4.0 * static_cast<double>(stats.acked_snapshots_against_baseline));
}

TEST(UdpTransport, OverAnEmulatedLinkSnapshotsArriveATickApartAndTheDelayIsTheLinks) {
    testing::RunningServer server(udp_config());
    simclient::LoadConfig lc = udp_load(server, 4, 3.0);
    simclient::Scenario scenario;
    scenario.stages = {{0.0, 4}, {3.0, 4}};
    scenario.groups.resize(1);
    scenario.groups[0].network.latency_ms = 40.0; // each way
    lc.scenario = scenario;
    const simclient::LoadReport report = testing::run_load(lc);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    server.stop();
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_GT(report.rtt_ms.p50, 80.0); // the link's 40 ms each way
    // The link delays every snapshot alike: a tick apart as it delivers them.
    EXPECT_NEAR(report.snapshot_socket_interarrival_ms.p50, 1000.0 / 30.0, 8.0);
    // Arrival is the link's delivery, so its 40 ms are not counted as the client's lag.
    EXPECT_GT(report.handling_lag_ms.count, 0u);
    EXPECT_LT(report.handling_lag_ms.p50, 20.0);
}

TEST(UdpTransport, UnderLossDuplicationAndReorderingTheReplicaStaysExactAndNothingIsStale) {
    testing::RunningServer server(udp_config());
    simclient::LoadConfig lc = udp_load(server, 4, 3.0);
    lc.udp_faults = {.loss = 0.2, .duplicate = 0.1, .reorder = 0.1}; // each way
    const simclient::LoadReport report = testing::run_load(lc);
    server.stop();
    // Every snapshot that arrived applied against a frame the client held (no
    // baseline_missing, no stale or unknown entity), and every audit was within half a
    // quantum: loss costs snapshots, never correctness.
    EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
    EXPECT_GT(report.audited_poses, 0u);
    EXPECT_LT(report.snapshots, server.stats().snapshots_sent); // some were lost
    EXPECT_GT(report.snapshots, server.stats().snapshots_sent / 3);
}

TEST(UdpTransport, HostileDatagramsAreDroppedByReasonWhileClientsKeepTheirSnapshots) {
    testing::RunningServer server(udp_config());
    testing::GoodClients good(udp_load(server, 4, 2.5));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));

    RawUdp raw(server.port());
    const std::vector<std::uint8_t> garbage(40, 0xff);
    raw.send(garbage);                                     // not_dsoc
    raw.send(std::vector<std::uint8_t>{0x44, 0x53, 0x4f}); // truncated
    raw.send(std::vector<std::uint8_t>(1300, 0));          // oversized
    std::vector<std::uint8_t> header;
    protocol::begin_datagram({DatagramKind::message, 5, 1}, header);
    auto wrong_version = header;
    wrong_version[4] = 9;
    raw.send(wrong_version); // wrong_version
    auto unknown_kind = header;
    unknown_kind[5] = 77;
    raw.send(unknown_kind); // unknown_kind
    protocol::begin_datagram({DatagramKind::snapshot, 5, 1}, header);
    raw.send(header);                   // unexpected_kind: only servers send snapshots
    raw.send(input_datagram(12345, 1)); // unknown_session
    // A response with a cookie this server never made.
    pb::Envelope hello;
    hello.mutable_client_hello()->set_protocol_version(protocol::kProtocolVersion);
    std::vector<std::uint8_t> forged;
    ASSERT_TRUE(protocol::write_response(77, protocol::ChallengeCookie{}, hello, forged));
    raw.send(forged); // forged_cookie
    // A request cut short of the full size: never answered (no amplification).
    std::vector<std::uint8_t> request;
    ASSERT_TRUE(protocol::write_request(78, hello, request));
    request.resize(200);
    raw.send(request); // truncated
    EXPECT_FALSE(raw.receive(std::chrono::milliseconds(200)).has_value())
        << "nothing above is ever answered";

    // A real session, then its datagrams from elsewhere and replayed.
    const std::uint64_t session = raw.handshake(79);
    ASSERT_NE(session, 0u);
    EXPECT_LT(raw.challenge_bytes, protocol::kMaxDatagramBytes) << "amplification";
    raw.send(input_datagram(session, 1));
    raw.send(input_datagram(session, 1)); // replayed
    RawUdp elsewhere(server.port());
    elsewhere.send(input_datagram(session, 2)); // wrong_source
    // The raw session keeps receiving snapshots of its own.
    EXPECT_TRUE(raw.receive_kind(DatagramKind::snapshot, std::chrono::seconds(1)).has_value());

    testing::expect_served(good, 100.0);
    server.stop();
    EXPECT_EQ(drops(server, UdpDrop::not_dsoc), 1u);
    EXPECT_EQ(drops(server, UdpDrop::truncated), 2u);
    EXPECT_EQ(drops(server, UdpDrop::oversized), 1u);
    EXPECT_EQ(drops(server, UdpDrop::wrong_version), 1u);
    EXPECT_EQ(drops(server, UdpDrop::unknown_kind), 1u);
    EXPECT_EQ(drops(server, UdpDrop::unexpected_kind), 1u);
    EXPECT_EQ(drops(server, UdpDrop::unknown_session), 1u);
    EXPECT_EQ(drops(server, UdpDrop::forged_cookie), 1u);
    EXPECT_EQ(drops(server, UdpDrop::replayed), 1u);
    EXPECT_EQ(drops(server, UdpDrop::wrong_source), 1u);
    EXPECT_EQ(drops(server, UdpDrop::rate_limited), 0u);
}

TEST(UdpTransport, ABurstIsReadManyToASystemCallEachDatagramWithItsOwnSource) {
    // The server reads what waits on its socket 32 datagrams to a system call: datagrams
    // from two sources, interleaved and sent faster than it reads them, must each be
    // judged by their own source, none lost or counted twice.
    testing::RunningServer server(udp_config());
    RawUdp raw(server.port());
    const std::uint64_t session = raw.handshake(81);
    ASSERT_NE(session, 0u);
    RawUdp elsewhere(server.port());
    constexpr std::uint32_t kPairs = 200;
    const std::vector<std::uint8_t> garbage(40, 0xff);
    for (std::uint32_t k = 0; k < kPairs; ++k) {
        elsewhere.send(input_datagram(session, 1000 + k)); // wrong_source
        raw.send(garbage);                                 // not_dsoc
    }
    // Read after stop(): the counters are the io thread's.
    std::this_thread::sleep_for(std::chrono::seconds(1));
    server.stop();
    EXPECT_EQ(server.udp_endpoint()->datagrams_received(), 2 + 2 * kPairs)
        << "with the handshake's two";
    EXPECT_EQ(drops(server, UdpDrop::wrong_source), kPairs);
    EXPECT_EQ(drops(server, UdpDrop::not_dsoc), kPairs);
    EXPECT_EQ(drops(server, UdpDrop::replayed), 0u);
}

/// The Disconnect the server sends `raw` within `timeout`, if any (other datagrams skipped).
std::optional<pb::Disconnect> disconnect_within(RawUdp& raw, std::chrono::milliseconds timeout) {
    const auto start = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - start < timeout) {
        const auto d = raw.receive_kind(DatagramKind::message, std::chrono::milliseconds(500));
        protocol::DatagramHeader h;
        std::span<const std::uint8_t> body;
        pb::Envelope message;
        if (d && protocol::read_datagram(*d, h, body) == protocol::DatagramError::none &&
            protocol::decode_payload(body, message) == protocol::DecodeError::none &&
            message.has_disconnect()) {
            return message.disconnect();
        }
    }
    return std::nullopt;
}

TEST(UdpTransport, ASilentClientIsTimedOutWithAReason) {
    auto c = udp_config();
    c.udp_timeout_ms = 600;
    testing::RunningServer server(c);
    RawUdp raw(server.port());
    const std::uint64_t session = raw.handshake(80);
    ASSERT_NE(session, 0u);
    const auto disconnect = disconnect_within(raw, std::chrono::seconds(3));
    server.stop();
    ASSERT_TRUE(disconnect.has_value());
    EXPECT_EQ(disconnect->reason(), pb::DISCONNECT_REASON_TIMED_OUT) << disconnect->text();
    EXPECT_EQ(server.stats().disconnects.at("timed_out"), 1u);
}

TEST(UdpTransport, InputDatagramsWhoseBodiesDoNotParseCountTowardTheRateCap) {
    // Every datagram costs a token of max_inputs_per_second, whatever its body: a flood of
    // well-formed datagrams whose input bodies do not parse ends the session as any flood.
    auto c = udp_config();
    testing::RunningServer server(c);
    RawUdp raw(server.port());
    const std::uint64_t session = raw.handshake(83);
    ASSERT_NE(session, 0u);
    for (std::uint32_t sequence = 1; sequence <= 1000; ++sequence) {
        std::vector<std::uint8_t> datagram = input_datagram(session, sequence);
        datagram.push_back(0); // a byte past its inputs: bad_body
        raw.send(datagram);
    }
    const auto disconnect = disconnect_within(raw, std::chrono::seconds(3));
    server.stop();
    ASSERT_TRUE(disconnect.has_value());
    EXPECT_EQ(disconnect->reason(), pb::DISCONNECT_REASON_INPUT_FLOOD) << disconnect->text();
    EXPECT_EQ(server.stats().disconnects.at("input_flood"), 1u);
    EXPECT_GT(drops(server, UdpDrop::bad_body), 0u);
}

TEST(UdpTransport, AClientThatFallsBehindGetsFewerSnapshotsUntilItAcknowledges) {
    auto c = udp_config();
    testing::RunningServer server(c);
    RawUdp raw(server.port());
    const std::uint64_t session = raw.handshake(85);
    ASSERT_NE(session, 0u);
    // Collects the ticks of the snapshots that arrive for `duration`, each tick once;
    // acknowledges the newest when `ack` (as every input of an honest client does).
    std::uint32_t sequence = 1;
    const auto listen = [&](std::chrono::milliseconds duration, bool ack) {
        std::vector<std::uint64_t> ticks;
        const auto until = std::chrono::steady_clock::now() + duration;
        while (std::chrono::steady_clock::now() < until) {
            const auto d = raw.receive_kind(DatagramKind::snapshot, std::chrono::milliseconds(50));
            protocol::DatagramHeader h;
            std::span<const std::uint8_t> body;
            protocol::SnapshotFragment f;
            if (d && protocol::read_datagram(*d, h, body) == protocol::DatagramError::none &&
                protocol::read_snapshot_body(body, f) == protocol::DatagramError::none &&
                f.count == 1 && (ticks.empty() || f.tick > ticks.back())) {
                ticks.push_back(f.tick);
            }
            if (ack && !ticks.empty()) {
                pb::ClientInput input;
                input.set_tick(sequence);
                std::vector<std::uint8_t> out;
                EXPECT_TRUE(protocol::write_input({DatagramKind::input, session, sequence++},
                                                  ticks.back(), std::span(&input, 1), out));
                raw.send(out);
            }
        }
        return ticks;
    };
    // The client acknowledges nothing for 2 s (60 ticks at 30 Hz): after the window,
    // one snapshot in kBehindInterval ticks.
    const std::vector<std::uint64_t> silent = listen(std::chrono::milliseconds(2000), false);
    ASSERT_GE(silent.size(), 2u);
    const std::uint64_t window = server::SnapshotPacer::unacked_window_at(c.tick_rate);
    ASSERT_EQ(window, 15u); // half a second at 30 Hz
    std::uint64_t after_window = 0;
    for (std::size_t i = 1; i < silent.size(); ++i) {
        if (silent[i] > silent.front() + window + 1) {
            EXPECT_GE(silent[i] - silent[i - 1], server::SnapshotPacer::kBehindInterval)
                << "tick " << silent[i];
            ++after_window;
        }
    }
    EXPECT_GE(after_window, 5u);
    EXPECT_LT(silent.size(), 35u); // not the 60 of full rate
    // Once it acknowledges, every tick again.
    const std::vector<std::uint64_t> acking = listen(std::chrono::milliseconds(1000), true);
    ASSERT_GE(acking.size(), 10u);
    std::size_t consecutive = 0;
    for (std::size_t i = 1; i < acking.size(); ++i) {
        consecutive += acking[i] == acking[i - 1] + 1 ? 1 : 0;
    }
    EXPECT_GT(consecutive, acking.size() / 2);
    server.stop(); // render_metrics() reads the I/O thread's state: after stop()
    // The metrics say why: the pace of a client behind.
    const std::string metrics = server.render_metrics();
    const std::string behind = "dsoc_udp_snapshots_paced_total{pace=\"behind\"} ";
    const auto at = metrics.find(behind);
    ASSERT_NE(at, std::string::npos) << metrics;
    EXPECT_GT(std::stod(metrics.substr(at + behind.size())), 20.0);
    EXPECT_GT(server.stats().snapshots_dropped, 20u);
    EXPECT_GT(server.stats().snapshots_paced.behind, 20u);
}

TEST(UdpTransport, ALostAcceptedIsSentAgainAndAResponseAfterTheCloseOpensNothing) {
    testing::RunningServer server(udp_config());
    RawUdp raw(server.port());
    const std::uint64_t session = raw.handshake(90);
    ASSERT_NE(session, 0u);
    const std::vector<std::uint8_t> first = raw.accepted;
    raw.send(raw.response); // as if the accepted datagram had been lost
    const auto again = raw.receive_kind(DatagramKind::accepted, std::chrono::seconds(1));
    ASSERT_TRUE(again.has_value());
    EXPECT_EQ(*again, first) << "the same session, the same reply";

    pb::Envelope bye;
    bye.mutable_disconnect()->set_reason(pb::DISCONNECT_REASON_CLIENT_QUIT);
    std::vector<std::uint8_t> goodbye;
    ASSERT_TRUE(
        protocol::write_envelope_datagram({DatagramKind::message, session, 1}, {}, &bye, goodbye));
    raw.send(goodbye);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    raw.send(raw.response); // replayed within the cookie's life: must not open a session
    EXPECT_FALSE(raw.receive_kind(DatagramKind::accepted, std::chrono::milliseconds(300)));
    server.stop();
    EXPECT_EQ(server.stats().clients_accepted, 1u);
    EXPECT_EQ(server.stats().disconnects.at("client_quit"), 1u);
    EXPECT_EQ(drops(server, UdpDrop::closed_session), 1u);
}

TEST(UdpTransport, AHelloTheServerRefusesIsAnsweredWithTheReasonInTheAcceptedDatagram) {
    const std::string key_file = ::testing::TempDir() + "/udp_transport_test.key";
    {
        std::ofstream out(key_file);
        out << protocol::format_token_key(protocol::generate_token_key()) << "\n";
    }
    auto c = udp_config();
    c.token_key_file = key_file;
    testing::RunningServer server(c);
    RawUdp raw(server.port());
    pb::Envelope reply;
    raw.handshake(91, RawUdp::plain_hello(), reply); // no token
    server.stop();
    ASSERT_TRUE(reply.has_disconnect());
    EXPECT_EQ(reply.disconnect().reason(), pb::DISCONNECT_REASON_UNAUTHORIZED)
        << reply.disconnect().text();
    EXPECT_EQ(server.stats().disconnects.at("unauthorized"), 1u);
}

TEST(UdpTransport, RequestsBeyondTheServersChallengeRateAreDroppedUnanswered) {
    auto c = udp_config();
    c.udp_challenge_rate = 3;
    testing::RunningServer server(c);
    RawUdp raw(server.port());
    for (int i = 0; i < 10; ++i) {
        raw.send_request(81, RawUdp::plain_hello());
    }
    const int challenges = raw.count_kind(DatagramKind::challenge, std::chrono::milliseconds(300));
    server.stop();
    // A burst of one second's worth (3) is answered; the refill in the few milliseconds
    // the burst takes is well under one more. No source's budget is spent.
    EXPECT_EQ(challenges, 3);
    EXPECT_EQ(drops(server, UdpDrop::over_challenge_rate), 7u);
    EXPECT_EQ(drops(server, UdpDrop::rate_limited), 0u);
}

TEST(UdpTransport, RequestsFromAnAddressDoNotSpendItsBudgetSoASpooferCannotLockItOut) {
    // A spoofer sends requests with the victim's source address (here: from the same
    // IPv4 address, another port). They prove nothing of the address, so they spend none
    // of its budget, and the victim still connects.
    auto c = udp_config();
    c.udp_handshake_rate = 3;
    testing::RunningServer server(c);
    RawUdp spoofer(server.port());
    for (std::uint64_t nonce = 1; nonce <= 40; ++nonce) {
        spoofer.send_request(nonce, RawUdp::plain_hello());
    }
    EXPECT_EQ(spoofer.count_kind(DatagramKind::challenge, std::chrono::milliseconds(200)), 40);
    RawUdp victim(server.port());
    EXPECT_NE(victim.handshake(77), 0u);
    server.stop();
    EXPECT_EQ(server.udp_endpoint()->challenges_sent(), 41u);
    EXPECT_EQ(drops(server, UdpDrop::rate_limited), 0u);
}

TEST(UdpTransport, ResponsesWithAValidCookieBeyondASourcesRateAreDroppedUnanswered) {
    auto c = udp_config();
    c.udp_handshake_rate = 3;
    testing::RunningServer server(c);
    RawUdp raw(server.port());
    const pb::Envelope hello = RawUdp::plain_hello();
    std::vector<std::vector<std::uint8_t>> responses;
    for (std::uint64_t nonce = 1; nonce <= 10; ++nonce) {
        raw.send_request(nonce, hello);
        const auto challenge = raw.receive_kind(DatagramKind::challenge, std::chrono::seconds(2));
        ASSERT_TRUE(challenge);
        protocol::DatagramHeader h;
        std::span<const std::uint8_t> cookie;
        ASSERT_EQ(protocol::read_datagram(*challenge, h, cookie), protocol::DatagramError::none);
        ASSERT_TRUE(protocol::write_response(nonce, cookie, hello, responses.emplace_back()));
    }
    for (const auto& response : responses) {
        raw.send(response);
    }
    const int accepted = raw.count_kind(DatagramKind::accepted, std::chrono::milliseconds(500));
    server.stop();
    EXPECT_EQ(accepted, 3);
    EXPECT_EQ(drops(server, UdpDrop::rate_limited), 7u);
    EXPECT_EQ(drops(server, UdpDrop::over_challenge_rate), 0u);
}

TEST(SourceKey, AnIpv4PeerOnADualStackSocketIsItsOwnAddressAndAnIpv6OneItsSlash64) {
    const auto at = [](const char* address) {
        return server::source_key(asio::ip::make_address(address));
    };
    // As it arrives on an IPv4 socket and as a dual-stack (::) socket reports it.
    EXPECT_EQ(at("192.0.2.7"), at("::ffff:192.0.2.7"));
    EXPECT_NE(at("::ffff:192.0.2.7"), at("::ffff:192.0.2.8"));
    EXPECT_FALSE(at("::ffff:192.0.2.7").v6);
    // An IPv6 /64 is one source, whatever its last 64 bits; the /64s apart in any bit
    // of their prefix are two.
    EXPECT_EQ(at("2001:db8:1:2::1"), at("2001:db8:1:2:ffff:ffff:ffff:ffff"));
    EXPECT_NE(at("2001:db8:1:2::1"), at("2001:db8:1:3::1"));    // the prefix's last bit
    EXPECT_NE(at("2001:db8:0:2::1"), at("2001:db8:8000:2::1")); // its 33rd bit
    EXPECT_NE(at("2001:db8:1:2::1"), at("a001:db8:1:2::1"));    // its first bit
    // An IPv6 prefix whose bits are an IPv4 address's is another source.
    EXPECT_NE(at("::c000:207"), at("192.0.2.7"));
    EXPECT_NE(at("0:0:c000:207::"), at("192.0.2.7"));
}

} // namespace
} // namespace dsoc
