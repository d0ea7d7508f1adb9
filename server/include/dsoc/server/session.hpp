#pragma once
// One client connection: framing, handshake, message dispatch, a bounded send
// queue and an orderly disconnect that always tells the client why.

#include "dsoc/protocol/framing.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/server_config.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace dsoc::server {

class Session;

/// What a session asks of the server. Called on the io_context thread.
class SessionHost {
public:
    virtual ~SessionHost() = default;
    /// A valid hello arrived; the host sends the ServerHello.
    virtual void on_hello(Session& session, const protocol::pb::ClientHello& hello) = 0;
    virtual void on_input(Session& session, const protocol::pb::ClientInput& input) = 0;
    /// The connection is closed; called exactly once per session.
    virtual void on_closed(Session& session) = 0;
};

class Session : public std::enable_shared_from_this<Session> {
public:
    enum class State : std::uint8_t { awaiting_hello, active, closing, closed };

    Session(boost::asio::ip::tcp::socket socket, std::uint32_t client_id,
            const ServerConfig& config, SessionHost& host);

    /// Starts reading and arms the handshake deadline.
    void start();

    /// Queues one message. Messages queued after disconnect() are dropped. When the
    /// queue would exceed max_send_queue_bytes the client is disconnected as too slow.
    void send(const protocol::pb::Envelope& message);

    /// Queues a Disconnect with `reason`, stops reading, and closes the socket once
    /// the queue has drained (or after a 1 s grace period).
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
    /// Why the connection ended (unspecified while open).
    [[nodiscard]] protocol::pb::DisconnectReason close_reason() const { return close_reason_; }

private:
    void read_some();
    void on_read(std::size_t bytes);
    void handle(const protocol::pb::Envelope& message);
    void handle_hello(const protocol::pb::ClientHello& hello);
    void enqueue(std::vector<std::uint8_t> frame);
    void write_next();
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
    protocol::pb::Envelope incoming_;
    std::deque<std::vector<std::uint8_t>> write_queue_;
    std::size_t queued_bytes_ = 0;
    bool writing_ = false;
    std::uint64_t bytes_sent_ = 0;
    std::uint64_t bytes_received_ = 0;
    std::string name_;
    std::string remote_;
    protocol::pb::DisconnectReason close_reason_ = protocol::pb::DISCONNECT_REASON_UNSPECIFIED;
};

} // namespace dsoc::server
