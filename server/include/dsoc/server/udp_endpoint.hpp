#pragma once
// The server's UDP socket (docs/protocol.md, "UDP transport"): the handshake and the
// routing of every datagram a client sends.
//
// The handshake keeps no state for a client until it proves its address:
// - request (padded to protocol::kMaxDatagramBytes) -> challenge: a cookie bound to the
//   source address, port, nonce and time (challenge_cookie.hpp); the answer is smaller
//   than the request, so a spoofed source cannot use the server as an amplifier;
// - response with that cookie and the hello -> a UdpConnection, its hello checked by the
//   host as over TCP (version, token, one connection per token client id), and the
//   accepted datagram with the session id.
// Responses with a valid cookie are rate-limited per source address (an IPv4 address, or
// an IPv6 /64); requests, which prove nothing of their source, only by the challenges
// the server answers a second in all. After it, a datagram reaches
// its connection only from the connection's own address, with its session id and a
// sequence number not taken before. Everything else is dropped and counted by reason
// (udp_drop.hpp); nothing a datagram holds can end another client's session.
//
// Threading: the io_context thread, but native_handle() (sending snapshots from the pool).

#include "dsoc/protocol/challenge_cookie.hpp"
#include "dsoc/server/source_key.hpp"
#include "dsoc/server/udp_connection.hpp"
#include "dsoc/server/udp_drop.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <sys/socket.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace dsoc::server {

class UdpEndpoint {
public:
    using Clock = std::chrono::steady_clock;
    /// Registers a new connection with the server, as it does a TCP connection it accepts;
    /// its hello follows at once (a full server refuses that).
    using OpenConnection = std::function<void(const std::shared_ptr<Connection>&)>;

    UdpEndpoint(boost::asio::io_context& io, const ServerConfig& config, ConnectionHost& host,
                std::function<std::uint32_t()> next_client_id, OpenConnection open);

    /// Binds `address`:`port` (0: any free port) and starts receiving; returns the port.
    /// Throws boost::system::system_error when it cannot bind.
    std::uint16_t start(const std::string& address, std::uint16_t port);
    /// Stops receiving (open connections are disconnected by the server).
    void stop();

    /// Sends one datagram now, without blocking (dropped when the kernel will not take it).
    /// Returns whether it went. io thread.
    bool send_to(const boost::asio::ip::udp::endpoint& peer, std::span<const std::uint8_t> bytes);
    /// For write_now() on pool threads.
    [[nodiscard]] int native_handle() { return socket_.native_handle(); }
    /// A connection closed: it is no longer routed to.
    void forget(const UdpConnection& connection);

    [[nodiscard]] const UdpDropCounts& drops() const { return drops_; }
    [[nodiscard]] std::uint64_t datagrams_received() const { return received_; }
    [[nodiscard]] std::uint64_t challenges_sent() const { return challenges_; }
    [[nodiscard]] std::size_t sessions() const { return by_session_.size(); }

private:
    /// Waits for the next datagram (asio's read: no arrival is missed between waits).
    void receive_next();
    /// After one datagram: the others already waiting, kReceiveBatch to a system call
    /// (recvmmsg), at most kMaxReceiveCalls calls before the io_context's other work.
    void receive_waiting();
    /// One datagram from `sender_`.
    void on_datagram(std::span<const std::uint8_t> datagram);
    void on_request(std::uint64_t nonce, std::span<const std::uint8_t> body);
    void on_response(std::uint64_t nonce, std::span<const std::uint8_t> body);
    /// The body checks of a handshake datagram (counted when it fails them); `cookie`
    /// and `hello` view the body's.
    [[nodiscard]] bool read_handshake(protocol::DatagramKind kind,
                                      std::span<const std::uint8_t> body,
                                      std::span<const std::uint8_t>& cookie,
                                      std::span<const std::uint8_t>& hello);
    struct Budget {
        double tokens = 0;
        Clock::time_point refilled;
    };
    /// Takes one token from `b`, refilled at `rate` a second up to `rate` (a burst of
    /// one second's worth) since it was last; false when it has none.
    static bool spend(Budget& b, double rate, Clock::time_point now);
    /// spend() from the sender's budget (its source_key()).
    [[nodiscard]] bool within_handshake_budget(Clock::time_point now);
    void sweep();
    void drop(UdpDrop reason) { ++drops_[static_cast<std::size_t>(reason)]; }

    const ServerConfig& config_;
    ConnectionHost& host_;
    std::function<std::uint32_t()> next_client_id_;
    OpenConnection open_;
    boost::asio::ip::udp::socket socket_;
    boost::asio::steady_timer sweep_timer_;
    protocol::TokenKey cookie_key_; ///< random per run: cookies die with the process
    /// One byte over the largest datagram, so that an oversized one is seen as such.
    using DatagramBuffer = std::array<std::uint8_t, protocol::kMaxDatagramBytes + 1>;
    DatagramBuffer buffer_{};
    /// receive_waiting()'s buffers and source addresses, one per datagram of a call: at
    /// most kReceiveBatch datagrams a call, kMaxReceiveCalls calls a read (so at most
    /// 1 + 32 * 8 datagrams handled before the io_context's other work).
    static constexpr std::size_t kReceiveBatch = 32;
    static constexpr int kMaxReceiveCalls = 8;
    std::vector<DatagramBuffer> receive_buffers_;
    std::vector<sockaddr_storage> receive_sources_;
    boost::asio::ip::udp::endpoint sender_; ///< the source of the datagram being handled
    std::vector<std::uint8_t> reply_;
    std::unordered_map<std::uint64_t, std::shared_ptr<UdpConnection>> by_session_;
    std::unordered_map<std::uint64_t, std::uint64_t> session_of_nonce_;
    /// Sessions closed lately, and when: their late datagrams are closed_session, not
    /// unknown_session (a client's goodbye goes twice; snapshots' inputs cross it).
    std::unordered_map<std::uint64_t, Clock::time_point> recently_closed_;
    std::unordered_map<SourceKey, Budget, SourceKeyHash> budgets_; ///< by source
    Budget challenge_budget_; ///< every source's requests (udp_challenge_rate)
    /// Nonces of sessions closed lately: their responses never open a new session.
    std::unordered_map<std::uint64_t, Clock::time_point> closed_nonces_;
    UdpDropCounts drops_{};
    std::uint64_t received_ = 0;
    std::uint64_t challenges_ = 0;
    bool stopped_ = false;
};

/// The cookie's view of an address.
[[nodiscard]] protocol::SourceAddress source_address(const boost::asio::ip::udp::endpoint& peer);

} // namespace dsoc::server
