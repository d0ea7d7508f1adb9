#pragma once
// One client's connection, whatever carries it: a TCP stream (Session, session.hpp) or
// UDP datagrams (UdpConnection, udp_connection.hpp). The server sees only this: it hands
// a connection its hello reply, its snapshots and its disconnect, and hears back through
// ConnectionHost.
//
// Threading: every call on the io_context thread, but write_now(), queue_now() and
// finish_queued(), which another thread may make while that thread waits for it (the
// hand-over, server.hpp).

#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/input_guard.hpp"
#include "dsoc/server/source_key.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::server {

class DatagramBatch;

class Connection;

/// What a connection asks of the server. Called on the io_context thread.
class ConnectionHost {
public:
    virtual ~ConnectionHost() = default;
    /// A hello with the right version and a sane name arrived; the host checks the
    /// connect token and sends the ServerHello (or disconnects).
    virtual void on_hello(Connection& connection, const protocol::pb::ClientHello& hello) = 0;
    /// An input within the rate cap, already checked and clamped (sanitize_input); over
    /// UDP also newer (ClientInput.tick) than every input before it.
    virtual void on_input(Connection& connection, const protocol::pb::ClientInput& input) = 0;
    /// The connection is closed; called exactly once per connection.
    virtual void on_closed(Connection& connection) = 0;
};

enum class Transport : std::uint8_t { tcp, udp };

/// Snapshots a client's pace skipped, by pace (SnapshotPacer).
struct SnapshotPaceCounts {
    std::uint64_t lagging = 0;
    std::uint64_t behind = 0;
};

class Connection : public std::enable_shared_from_this<Connection> {
public:
    using Clock = std::chrono::steady_clock;
    enum class State : std::uint8_t { awaiting_hello, active, closing, closed };

    virtual ~Connection() = default;
    Connection(const Connection&) = delete;
    Connection& operator=(const Connection&) = delete;

    [[nodiscard]] virtual Transport transport() const = 0;

    /// Sends one message (the hello reply, a pong). Messages sent after disconnect()
    /// are dropped.
    virtual void send(const protocol::pb::Envelope& message) = 0;

    /// Asks whether this client can take the snapshot of `tick` now. False drops it
    /// (latest wins; counted in snapshots_dropped()); may disconnect a client that has not
    /// taken one for too long.
    [[nodiscard]] virtual bool offer_snapshot(Clock::time_point now, std::uint64_t tick) = 0;

    /// Queues a snapshot frame (ClientTick::frame, in this transport's form); call only
    /// after offer_snapshot() returned true. Takes the bytes of `frame` and leaves in it
    /// an empty buffer with spare capacity.
    virtual void send_snapshot_frame(std::vector<std::uint8_t>& frame) = 0;

    /// The hand-over's fast path for a snapshot frame, in three steps, so that the
    /// server can hand many clients' frames to the kernel on several threads:
    /// - writable_now(), on the io thread: true when the frame may go to the kernel
    ///   directly instead of through send_snapshot_frame().
    /// - write_now(): hands the frame to the kernel without blocking and returns how many
    ///   of its bytes went (0 when none). It may run on another thread, while the io
    ///   thread waits for it: nothing else may touch this connection meanwhile.
    /// - finish_write_now(), on the io thread: counts what was written and queues what
    ///   was not (a transport that cannot queue drops it). Leaves in `frame` an empty
    ///   buffer with spare capacity; returns true when some or all of it went to a queue.
    [[nodiscard]] virtual bool writable_now() const = 0;
    [[nodiscard]] virtual std::size_t write_now(std::span<const std::uint8_t> frame) noexcept = 0;
    virtual bool finish_write_now(std::vector<std::uint8_t>& frame, std::size_t written) = 0;
    /// write_now() in two steps, for a transport of datagrams, so that one system call
    /// writes many clients' frames: queue_now() puts the frame's datagrams in `batch`
    /// (false: this transport does not batch, call write_now()); after batch.send(),
    /// finish_queued() returns what write_now() would have and takes the frame as
    /// written. At most one queue_now() per connection and batch, each followed by
    /// finish_queued(); on the thread write_now() may use, under the same rule.
    virtual bool queue_now(std::span<const std::uint8_t> /*frame*/,
                           DatagramBatch& /*batch*/) noexcept {
        return false;
    }
    [[nodiscard]] virtual std::size_t finish_queued(const DatagramBatch& /*batch*/) noexcept {
        return 0;
    }

    /// Tells the client `reason` as well as the transport can, stops handling its
    /// messages and closes; on_closed() follows (at once or after a grace period).
    virtual void disconnect(protocol::pb::DisconnectReason reason, const std::string& text) = 0;
    /// A connection still waiting for its hello must say it within `within` from now (when
    /// that is sooner than its own deadline), or is closed with handshake_timeout: what a
    /// source with many connections waiting gets (ServerConfig::max_pending_per_source).
    /// Nothing over UDP, whose connections open with their hello.
    virtual void hurry_hello(std::chrono::milliseconds within) { (void)within; }

    /// The newest snapshot tick the client said it applied (acknowledged-delta transports
    /// only; nothing over TCP, or before the first acknowledgement).
    [[nodiscard]] virtual std::optional<std::uint64_t> acked_tick() const { return {}; }

    [[nodiscard]] State state() const { return state_; }
    [[nodiscard]] bool active() const { return state_ == State::active; }
    [[nodiscard]] std::uint32_t client_id() const { return client_id_; }
    [[nodiscard]] std::uint32_t entity_id() const { return entity_id_; }
    void set_entity_id(std::uint32_t id) { entity_id_ = id; }
    void mark_active() { state_ = State::active; }
    [[nodiscard]] const std::string& name() const { return name_; }
    [[nodiscard]] const std::string& remote() const { return remote_; }
    /// The source the peer's address counts as (source_key.hpp).
    [[nodiscard]] const SourceKey& source() const { return source_; }
    [[nodiscard]] std::uint64_t bytes_sent() const { return bytes_sent_; }
    [[nodiscard]] std::uint64_t bytes_received() const { return bytes_received_; }
    [[nodiscard]] std::size_t queued_bytes() const { return queued_bytes_; }
    /// Largest queued_bytes() seen over the connection's life.
    [[nodiscard]] std::size_t peak_queued_bytes() const { return peak_queued_bytes_; }
    [[nodiscard]] std::uint64_t snapshots_dropped() const { return snapshots_dropped_; }
    /// Of snapshots_dropped(), those a UDP client's pace skipped (SnapshotPacer).
    [[nodiscard]] virtual SnapshotPaceCounts snapshots_paced() const { return {}; }
    [[nodiscard]] std::uint64_t inputs_dropped() const { return limiter_.dropped(); }
    [[nodiscard]] std::uint64_t inputs_clamped() const { return inputs_clamped_; }
    /// The client id its connect token proved (0 on insecure servers).
    [[nodiscard]] std::uint64_t token_client_id() const { return token_client_id_; }
    void set_token_client_id(std::uint64_t id) { token_client_id_ = id; }
    /// Why the connection ended (unspecified while open).
    [[nodiscard]] protocol::pb::DisconnectReason close_reason() const { return close_reason_; }

protected:
    Connection(std::uint32_t client_id, int max_inputs_per_second, ConnectionHost& host)
        : client_id_(client_id), host_(host), limiter_(max_inputs_per_second, Clock::now()) {}

    /// The checks every transport makes on a hello: the protocol version and the name's
    /// length. False: the client has been disconnected (the reason says which).
    bool accept_hello(const protocol::pb::ClientHello& hello);
    /// The rate cap on one client message (an input or a ping): false when it is
    /// dropped over the cap or the client was disconnected for a flood.
    [[nodiscard]] bool admit_message();
    /// Checks and clamps one input (already past the rate cap) and hands it to the host.
    /// False: the client has been disconnected with invalid_input.
    bool deliver_input(const protocol::pb::ClientInput& input);
    /// The pong that answers `ping`.
    [[nodiscard]] static protocol::pb::Envelope pong_for(const protocol::pb::Ping& ping);
    /// What every transport's disconnect() does first: false when the connection is
    /// already closing or closed (a second reason changes nothing); otherwise logs the
    /// reason and keeps it as close_reason(), and the transport goes on to tell the client.
    [[nodiscard]] bool begin_disconnect(protocol::pb::DisconnectReason reason,
                                        const std::string& text);

    SourceKey source_;
    std::uint32_t client_id_;
    std::uint32_t entity_id_ = 0;
    ConnectionHost& host_;
    State state_ = State::awaiting_hello;
    InputRateLimiter limiter_;
    protocol::pb::ClientInput input_; // scratch: the clamped copy
    std::size_t queued_bytes_ = 0;
    std::size_t peak_queued_bytes_ = 0;
    std::uint64_t snapshots_dropped_ = 0;
    std::uint64_t inputs_clamped_ = 0;
    std::uint64_t token_client_id_ = 0;
    std::uint64_t bytes_sent_ = 0;
    std::uint64_t bytes_received_ = 0;
    std::string name_;
    std::string remote_;
    protocol::pb::DisconnectReason close_reason_ = protocol::pb::DISCONNECT_REASON_UNSPECIFIED;
};

} // namespace dsoc::server
