#pragma once
// One client connection: framing, handshake, message dispatch, a bounded send
// queue and an orderly disconnect that always tells the client why.

#include "dsoc/protocol/framing.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/input_guard.hpp"
#include "dsoc/server/server_config.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace dsoc::server {

class Session;

/// What a session asks of the server. Called on the io_context thread.
class SessionHost {
public:
    virtual ~SessionHost() = default;
    /// A hello with the right version and a sane name arrived; the host checks the
    /// connect token and sends the ServerHello (or disconnects).
    virtual void on_hello(Session& session, const protocol::pb::ClientHello& hello) = 0;
    /// An input within the rate cap, already checked and clamped (sanitize_input).
    virtual void on_input(Session& session, const protocol::pb::ClientInput& input) = 0;
    /// The connection is closed; called exactly once per session.
    virtual void on_closed(Session& session) = 0;
};

/// Threading: every call on the io_context thread that runs the socket, but
/// write_now(), which another thread may make while that thread waits for it.
///
/// Memory: at most one snapshot is queued per client (being written or waiting);
/// a client that cannot take a snapshot when one is due simply skips it (see
/// offer_snapshot), so the queue holds one snapshot plus small replies, and it can
/// never exceed max_send_queue_bytes without the client being disconnected.
class Session : public std::enable_shared_from_this<Session> {
public:
    using Clock = std::chrono::steady_clock;

    enum class State : std::uint8_t { awaiting_hello, active, closing, closed };

    Session(boost::asio::ip::tcp::socket socket, std::uint32_t client_id,
            const ServerConfig& config, SessionHost& host);

    /// Starts reading and arms the handshake deadline.
    void start();

    /// Handles received bytes exactly as if they had been read from the socket:
    /// framing, decoding, the handshake, the rate cap and dispatch to the host.
    /// start() feeds it from the socket; fuzzers and tests call it directly.
    void receive(std::span<const std::uint8_t> bytes);

    /// Queues one message. Messages queued after disconnect() are dropped. When the
    /// queue would exceed max_send_queue_bytes the client is disconnected as too slow.
    void send(const protocol::pb::Envelope& message);

    /// Asks whether this client can take a snapshot now: true when it is active and
    /// its previous snapshot has been handed to the socket. False drops this tick's
    /// snapshot for it (latest wins: the next one is built from newer state, as a
    /// delta against what was really sent); once a snapshot has waited longer than
    /// slow_client_timeout_ms the client is disconnected with too_slow.
    [[nodiscard]] bool offer_snapshot(Clock::time_point now);

    /// Queues a snapshot; call only after offer_snapshot() returned true.
    void send_snapshot(const protocol::pb::Envelope& message);
    /// The same for a snapshot already encoded as one frame (encode_frame()): takes
    /// the bytes of `frame` and leaves in it an empty buffer with spare capacity
    /// (a previous snapshot's, once written), so a client's snapshots cycle between
    /// two buffers without allocating.
    void send_snapshot_frame(std::vector<std::uint8_t>& frame);

    /// The hand-over's fast path for a snapshot frame, in three steps, so that the
    /// server can hand many clients' frames to the kernel on several threads:
    /// - writable_now(), on the io thread: true when the client is active, has no
    ///   snapshot queued and has nothing queued or being written; the frame may then go
    ///   to the socket directly, in order, instead of through the queue.
    /// - write_now(): hands as much of `frame` as the kernel takes without blocking and
    ///   returns how many bytes that was (0 when it took none or failed). It may run on
    ///   another thread, while the io thread waits for it: nothing else may touch this
    ///   session meanwhile.
    /// - finish_write_now(), on the io thread: counts the bytes written and queues the
    ///   rest of the frame as send_snapshot_frame() does (a frame started is never cut,
    ///   so a rest goes out whatever the queue's limit). With nothing written the whole
    ///   frame takes the queued path, whose write retries and reports any socket error.
    ///   Leaves in `frame` an empty buffer with spare capacity; returns false when the
    ///   kernel took the whole frame, true when some or all of it went to the queue.
    [[nodiscard]] bool writable_now() const;
    [[nodiscard]] std::size_t write_now(std::span<const std::uint8_t> frame) noexcept;
    bool finish_write_now(std::vector<std::uint8_t>& frame, std::size_t written);

    /// Drops every queued frame but the one being written (a frame is never cut),
    /// queues a Disconnect with `reason` behind it, grows the socket's send buffer so
    /// that both go to the kernel at once, stops handling messages and half-closes;
    /// the socket is closed when the peer closes or after a 1 s grace period. A client
    /// that reads again, even after that, receives the reason, then end-of-file
    /// (within the kernel's limits: net.core.wmem_max, the life of an orphaned socket).
    void disconnect(protocol::pb::DisconnectReason reason, const std::string& text);

    [[nodiscard]] State state() const { return state_; }
    [[nodiscard]] bool active() const { return state_ == State::active; }
    [[nodiscard]] std::uint32_t client_id() const { return client_id_; }
    [[nodiscard]] std::uint32_t entity_id() const { return entity_id_; }
    void set_entity_id(std::uint32_t id) { entity_id_ = id; }
    void mark_active() { state_ = State::active; }
    [[nodiscard]] const std::string& name() const { return name_; }
    [[nodiscard]] const std::string& remote() const { return remote_; }
    [[nodiscard]] std::uint64_t bytes_sent() const { return bytes_sent_; }
    [[nodiscard]] std::uint64_t bytes_received() const { return bytes_received_; }
    [[nodiscard]] std::size_t queued_bytes() const { return queued_bytes_; }
    /// Largest queued_bytes() seen over the session's life.
    [[nodiscard]] std::size_t peak_queued_bytes() const { return peak_queued_bytes_; }
    [[nodiscard]] std::uint64_t snapshots_dropped() const { return snapshots_dropped_; }
    [[nodiscard]] std::uint64_t inputs_dropped() const { return limiter_.dropped(); }
    [[nodiscard]] std::uint64_t inputs_clamped() const { return inputs_clamped_; }
    /// The client id its connect token proved (0 on insecure servers).
    [[nodiscard]] std::uint64_t token_client_id() const { return token_client_id_; }
    void set_token_client_id(std::uint64_t id) { token_client_id_ = id; }
    /// Why the connection ended (unspecified while open).
    [[nodiscard]] protocol::pb::DisconnectReason close_reason() const { return close_reason_; }

private:
    void read_some();
    void on_read(std::size_t bytes);
    void handle(const protocol::pb::Envelope& message);
    void handle_hello(const protocol::pb::ClientHello& hello);
    void enqueue(std::vector<std::uint8_t> frame, bool snapshot);
    void handle_client_message(const protocol::pb::Envelope& message);
    void write_next();
    void make_room_for_queue();
    void close_now();

    boost::asio::ip::tcp::socket socket_;
    boost::asio::steady_timer deadline_;
    std::uint32_t client_id_;
    std::uint32_t entity_id_ = 0;
    const ServerConfig& config_;
    SessionHost& host_;
    State state_ = State::awaiting_hello;
    protocol::FrameDecoder decoder_;
    std::array<std::uint8_t, 16 * 1024> read_buffer_{};
    struct QueuedFrame {
        std::vector<std::uint8_t> bytes;
        bool snapshot = false;
    };
    std::deque<QueuedFrame> write_queue_;
    std::vector<std::uint8_t> spare_frame_; ///< a written snapshot's buffer, for reuse
    std::size_t queued_bytes_ = 0;
    std::size_t peak_queued_bytes_ = 0;
    bool snapshot_queued_ = false; ///< a snapshot frame is in write_queue_
    Clock::time_point snapshot_queued_at_;
    std::uint64_t snapshots_dropped_ = 0;
    std::uint64_t inputs_clamped_ = 0;
    std::uint64_t token_client_id_ = 0;
    InputRateLimiter limiter_;
    protocol::pb::ClientInput input_; // scratch: the clamped copy
    bool writing_ = false;
    std::uint64_t bytes_sent_ = 0;
    std::uint64_t bytes_received_ = 0;
    std::string name_;
    std::string remote_;
    protocol::pb::DisconnectReason close_reason_ = protocol::pb::DISCONNECT_REASON_UNSPECIFIED;
};

} // namespace dsoc::server
