#pragma once
// One headless simulated client session: resolves, connects (over TCP, or over UDP with
// udp_link.hpp), says hello, sends its behaviour's input every tick, decodes the
// snapshots (compact over TCP, acknowledged deltas over UDP) into its own replica of
// the world and checks the protocol's invariants - including, when it asks the server
// for audits, that every replicated pose is within half a quantum of the server's own.
// Every way it can fail is named (ClientStats::failure, failure_reason.hpp).

#include "dsoc/protocol/acked_snapshot.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/framing.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/simclient/client_stats.hpp"
#include "dsoc/simclient/delay_line.hpp"
#include "dsoc/simclient/input_model.hpp"
#include "dsoc/simclient/load_config.hpp"
#include "dsoc/simclient/scenario.hpp"
#include "dsoc/simclient/udp_link.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::simclient {

class SimClient;

/// What a LoadRun tells one session. The hooks run from the io_context (posted, never
/// from inside the session's own handlers).
struct SessionSetup {
    /// Behaviour and network conditions; nullptr: a wanderer without added latency.
    const ClientGroup* group = nullptr;
    int index = 0; ///< names the client (name_prefix + index) and its token id
    /// Decode every snapshot into the replica, check it and sample what it holds
    /// (LoadConfig::check_every); otherwise acknowledge each unread. A spectator decodes
    /// either way (it picks whom to watch from what it knows), but samples only when set.
    bool checks_snapshots = true;
    /// The server this session connects to (one of LoadConfig's).
    std::string host = "127.0.0.1";
    std::uint16_t port = 27960;
    std::uint64_t session = 0;      ///< this session's number in the run (seeds its inputs)
    double connect_timeout_s = 5.0; ///< resolve + connect + hello
    /// A server shutdown announced before this fails the session; after it, it is the
    /// expected end.
    std::chrono::steady_clock::time_point run_end = std::chrono::steady_clock::time_point::max();
    std::function<void(double)> on_interarrival; ///< each snapshot interarrival [ms]
    std::function<void(SimClient&)> on_failure;  ///< once, when stats().failure is set
    std::function<void(SimClient&)> on_closed;   ///< once, when finished() became true
};

class SimClient : public std::enable_shared_from_this<SimClient>, private KnownEntities {
public:
    SimClient(boost::asio::io_context& io, const LoadConfig& config, SessionSetup setup);

    /// Resolves and connects; the rest follows from the server's answers.
    void start();
    /// Says goodbye (Disconnect client_quit), then reads until the server closes; a
    /// session still connecting closes at once.
    void stop();

    [[nodiscard]] const ClientStats& stats() const { return stats_; }
    /// Its run replaced it with a session at the next server (ClientStats::failed_over).
    void mark_failed_over() { stats_.failed_over = true; }
    [[nodiscard]] const SessionSetup& setup() const { return setup_; }
    [[nodiscard]] std::string name() const;
    [[nodiscard]] bool connected() const { return state_ == State::active; }
    /// Resolving, connecting or awaiting the server hello.
    [[nodiscard]] bool connecting() const {
        return state_ == State::connecting || state_ == State::awaiting_hello;
    }
    [[nodiscard]] bool finished() const { return state_ == State::closed; }
    /// Entities in the replica right now (0 for a session that does not decode).
    [[nodiscard]] std::size_t known() const;
    /// The replica over TCP (quantized poses as decoded; empty over UDP).
    [[nodiscard]] const protocol::SnapshotDecoder& replica() const { return replica_; }
    /// The replica over UDP (empty over TCP).
    [[nodiscard]] const protocol::AckedSnapshotDecoder& acked_replica() const {
        return acked_replica_;
    }

private:
    enum class State : std::uint8_t { idle, connecting, awaiting_hello, active, stopping, closed };

    void on_resolved(const boost::asio::ip::tcp::resolver::results_type& endpoints);
    void on_connected();
    [[nodiscard]] protocol::pb::Envelope make_hello() const;
    void connect_udp(const boost::asio::ip::tcp::resolver::results_type& endpoints);
    void receive_udp(const protocol::pb::Envelope& message);
    void send_udp(const protocol::pb::Envelope& message);
    void apply_acked_snapshot(const protocol::pb::Snapshot& snapshot);
    /// A discarding session's handling of a snapshot (LoadConfig::check_every): counted,
    /// its own entity looked for among the enters, acknowledged unread.
    void discard_snapshot(const protocol::pb::Snapshot& snapshot);
    /// The tick the next input acknowledges (0: none yet): the newest frame applied, or
    /// by a discarding session the newest snapshot received.
    [[nodiscard]] std::uint64_t acknowledged_tick() const;
    /// Applies `snapshot` to `replica` (either decoder), checks its audit, counts it.
    template <typename Replica>
    void apply_and_audit(Replica& replica, const protocol::pb::Snapshot& snapshot);
    /// The interarrival and tick checks every snapshot gets, whatever the transport.
    void count_snapshot(const protocol::pb::Snapshot& snapshot);
    [[nodiscard]] bool knows(std::uint32_t id) const override;
    void players(std::vector<std::uint32_t>& out) const override;
    void read_some();
    void consume(std::span<const std::uint8_t> bytes);
    void on_read_error(const boost::system::error_code& ec);
    void handle(const protocol::pb::Envelope& message);
    void on_server_hello(const protocol::pb::ServerHello& hello);
    void on_disconnect(const protocol::pb::Disconnect& disconnect);
    void apply_snapshot(const protocol::pb::Snapshot& snapshot);
    /// The server's tick period (its tick rate from the ServerHello).
    [[nodiscard]] std::chrono::nanoseconds tick_period() const {
        return std::chrono::nanoseconds(1'000'000'000LL / tick_rate_);
    }
    void schedule_input();
    void send_input();
    /// Over UDP the input, and with it the acknowledgement, leaves as soon as a snapshot
    /// is applied, as a game client's does when its frame runs on the snapshot it just
    /// got (at 60 frames a second or more, within a few milliseconds); the input clock
    /// then sends a tick and a half later, and a tick apart after that, only while no
    /// snapshot comes. On a clock of its own phase the acknowledgement would wait up to a
    /// tick, and every snapshot coded against a baseline a tick older costs both ends
    /// more (docs/simclient.md). Never within half a tick of the last input.
    void send_input_on_snapshot();
    void send(const protocol::pb::Envelope& message, bool goodbye = false);
    void queue_frame(std::span<const std::uint8_t> frame, bool goodbye);
    void write_next();
    void error(const std::string& kind);
    void fail(std::string_view reason, const std::string& detail);
    void close();

    boost::asio::io_context& io_;
    const LoadConfig& config_;
    SessionSetup setup_;
    State state_ = State::idle;
    boost::asio::ip::tcp::resolver resolver_;
    boost::asio::ip::tcp::socket socket_;
    boost::asio::steady_timer input_timer_;
    boost::asio::steady_timer close_timer_;
    boost::asio::steady_timer connect_timer_;
    std::optional<DelayLine> delay_out_; // the group's latency, when it has one
    std::optional<DelayLine> delay_in_;
    protocol::FrameDecoder decoder_;
    std::array<std::uint8_t, 16 * 1024> read_buffer_{}; // a read may hold several frames
    std::vector<std::uint8_t> pending_;                 // frames not yet handed to the socket
    std::vector<std::uint8_t> in_flight_;               // the frames of the write in progress
    std::vector<std::uint8_t> frame_; // one encoded frame on its way to a delay line
    bool writing_ = false;
    bool goodbye_sent_ = false;
    protocol::SnapshotDecoder replica_;
    std::unique_ptr<UdpLink> udp_;                     // over UDP
    protocol::AckedSnapshotDecoder acked_replica_;     // over UDP
    std::chrono::steady_clock::time_point last_heard_; // over UDP: the last envelope received
    ClientStats stats_;
    InputModel input_model_;
    std::uint64_t last_snapshot_tick_ = 0;
    /// What a session that does not decode acknowledges: the newest snapshot tick
    /// received (never going back, as a decoder's newest frame does not); 0: none.
    std::uint64_t acked_unread_tick_ = 0;
    std::uint64_t input_seq_ = 0;
    int tick_rate_ = 30;
    std::chrono::steady_clock::time_point started_at_;
    std::chrono::steady_clock::time_point active_since_;
    std::chrono::steady_clock::time_point last_snapshot_at_;
    /// Over UDP, while a message is handled: when it arrived, the kernel's receive time of
    /// its last datagram, or when the emulated link of the client's group delivered it
    /// (that time plus the group's latency). Unset over TCP.
    std::optional<std::chrono::steady_clock::time_point> arrival_;
    std::optional<std::chrono::steady_clock::time_point> last_snapshot_arrival_;
    /// When the next input falls due (one tick after the last); it leaves at the next
    /// whole millisecond, with the other clients' inputs due in that millisecond.
    std::chrono::steady_clock::time_point next_input_at_;
    std::chrono::steady_clock::time_point last_input_at_; ///< when the last input left
    std::uint64_t input_clock_armed_ = 0;                 ///< waits armed on input_timer_
};

} // namespace dsoc::simclient
