#pragma once
// One client's TCP connection: framing, handshake, message dispatch, a bounded send
// queue and an orderly disconnect that always tells the client why.

#include "dsoc/protocol/framing.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/connection.hpp"
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

/// Threading: every call on the io_context thread that runs the socket, but
/// write_now(), which another thread may make while that thread waits for it.
///
/// Memory: at most one snapshot is queued per client (being written or waiting);
/// a client that cannot take a snapshot when one is due simply skips it (see
/// offer_snapshot), so the queue holds one snapshot plus small replies, and it can
/// never exceed max_send_queue_bytes without the client being disconnected.
class Session final : public Connection {
public:
    Session(boost::asio::ip::tcp::socket socket, std::uint32_t client_id,
            const ServerConfig& config, ConnectionHost& host);

    [[nodiscard]] Transport transport() const override { return Transport::tcp; }

    /// Starts reading and arms the handshake deadline.
    void start();

    /// Handles received bytes exactly as if they had been read from the socket:
    /// framing, decoding, the handshake, the rate cap and dispatch to the host.
    /// start() feeds it from the socket; fuzzers and tests call it directly.
    void receive(std::span<const std::uint8_t> bytes);

    /// Queues one message. Messages queued after disconnect() are dropped. When the
    /// queue would exceed max_send_queue_bytes the client is disconnected as too slow.
    void send(const protocol::pb::Envelope& message) override;
    void hurry_hello(std::chrono::milliseconds within) override;

    /// Asks whether this client can take a snapshot now: true when it is active and
    /// its previous snapshot has been handed to the socket. False drops this tick's
    /// snapshot for it (latest wins: the next one is built from newer state, as a
    /// delta against what was really sent); once a snapshot has waited longer than
    /// slow_client_timeout_ms the client is disconnected with too_slow.
    [[nodiscard]] bool offer_snapshot(Clock::time_point now, std::uint64_t tick) override;

    /// Queues a snapshot; call only after offer_snapshot() returned true.
    void send_snapshot(const protocol::pb::Envelope& message);
    /// The same for a snapshot already encoded as one frame (encode_frame()): takes
    /// the bytes of `frame` and leaves in it an empty buffer with spare capacity
    /// (a previous snapshot's, once written), so a client's snapshots cycle between
    /// two buffers without allocating.
    void send_snapshot_frame(std::vector<std::uint8_t>& frame) override;

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
    [[nodiscard]] bool writable_now() const override;
    [[nodiscard]] std::size_t write_now(std::span<const std::uint8_t> frame) noexcept override;
    bool finish_write_now(std::vector<std::uint8_t>& frame, std::size_t written) override;

    /// Drops every queued frame but the one being written (a frame is never cut),
    /// queues a Disconnect with `reason` behind it, grows the socket's send buffer so
    /// that both go to the kernel at once, stops handling messages and half-closes;
    /// the socket is closed when the peer closes or after a 1 s grace period. A client
    /// that reads again, even after that, receives the reason, then end-of-file
    /// (within the kernel's limits: net.core.wmem_max, the life of an orphaned socket).
    void disconnect(protocol::pb::DisconnectReason reason, const std::string& text) override;

private:
    void read_some();
    /// Closes the connection with handshake_timeout unless it says its hello within
    /// `within` from now (replacing the deadline set before).
    void await_hello(std::chrono::milliseconds within);
    void on_read(std::size_t bytes);
    void handle(const protocol::pb::Envelope& message);
    void handle_hello(const protocol::pb::ClientHello& hello);
    void enqueue(std::vector<std::uint8_t> frame, bool snapshot);
    void handle_client_message(const protocol::pb::Envelope& message);
    [[nodiscard]] std::shared_ptr<Session> self() {
        return std::static_pointer_cast<Session>(shared_from_this());
    }
    void write_next();
    void make_room_for_queue();
    void close_now();

    boost::asio::ip::tcp::socket socket_;
    boost::asio::steady_timer deadline_;
    const ServerConfig& config_;
    protocol::FrameDecoder decoder_;
    std::array<std::uint8_t, 16 * 1024> read_buffer_{};
    struct QueuedFrame {
        std::vector<std::uint8_t> bytes;
        bool snapshot = false;
    };
    std::deque<QueuedFrame> write_queue_;
    std::vector<std::uint8_t> spare_frame_; ///< a written snapshot's buffer, for reuse
    bool snapshot_queued_ = false;          ///< a snapshot frame is in write_queue_
    Clock::time_point snapshot_queued_at_;
    bool writing_ = false;
};

} // namespace dsoc::server
