#pragma once
// A simulated client's UDP transport (docs/protocol.md, "UDP transport"): the handshake
// (request padded to a full datagram, the server's challenge cookie echoed in the
// response, retried until accepted), message and input datagrams (each input datagram
// carries the newest snapshot tick applied and the last kMaxRedundantInputs inputs, so
// one lost datagram loses no input), and the reassembly of snapshot fragments. What it
// receives from the server it hands over as envelopes; datagrams from elsewhere, of
// another session, replayed or malformed are dropped and counted. Each datagram's arrival
// is the kernel's receive timestamp, so a client's figures can tell the server's and the
// network's timing from its own delay in handling what arrived.
//
// Threading: the io_context's thread only. Lifetime: the handlers are not called after
// close().

#include "dsoc/protocol/datagram.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/simclient/receive_time.hpp"
#include "dsoc/simclient/scenario.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace dsoc::simclient {

class UdpLink {
public:
    struct Handlers {
        /// A message from the server: the hello reply (or the disconnect refusing it), a
        /// pong, a disconnect, or a snapshot (Envelope.snapshot, reassembled).
        std::function<void(const protocol::pb::Envelope&)> on_envelope;
        /// Bytes of a datagram (ours or not) received, and of one sent.
        std::function<void(std::size_t)> on_bytes_down;
        std::function<void(std::size_t)> on_bytes_up;
        /// Something the server sent that a correct server never sends (a protocol error).
        std::function<void(const std::string&)> on_error;
        /// Before the session is accepted: at the last of the addresses the host said
        /// nothing listens on the port (ICMP port unreachable, read as a receive error).
        /// `why` names each address tried and what became of it, joined by "; ". Called
        /// once: the link stays open and the owner decides; later refusals, and any after
        /// the session is accepted (a lost server shows as silence), are ignored.
        std::function<void(const std::string& why)> on_refused;
        /// The socket can no longer be read: woken with nothing to read on a socket shut
        /// down for reading (POLLRDHUP), or its wait failed. The link has stopped reading;
        /// the owner decides (`why` says what happened). An empty or malformed datagram
        /// is never a reason (anyone may send one): it is dropped and counted.
        std::function<void(const std::string&)> on_socket_error;
    };
    /// `faults`: emulated on each datagram either way (dropped, delivered twice, or held
    /// back and delivered right after the next one).
    UdpLink(boost::asio::io_context& io, Handlers handlers, const DatagramFaults& faults,
            std::uint64_t seed);

    /// Opens a socket towards the first of `servers` (the addresses a name resolved to)
    /// and sends the request carrying `hello` (retried every 250 ms, the response
    /// likewise, until the accepted datagram arrives); where the host answers that
    /// nothing listens, the next address. Returns false (with `error`) when there is no
    /// address, the socket cannot be opened or the hello does not fit.
    /// `owner` is the SimClient that owns this link: kept alive by the handshake's pending
    /// retries; a receive wait that completes after it is gone does nothing.
    bool connect(std::vector<boost::asio::ip::udp::endpoint> servers,
                 const protocol::pb::Envelope& hello, std::shared_ptr<void> owner,
                 std::string& error);
    /// A message datagram (ping, disconnect), once the session is accepted.
    void send_message(const protocol::pb::Envelope& message);
    /// An input datagram with `input` and the inputs sent before it, and `ack`.
    void send_input(const protocol::pb::ClientInput& input, std::uint64_t ack);
    void close();

    [[nodiscard]] bool accepted() const { return session_ != 0; }
    /// Datagrams dropped: not from the server, another session, replayed, malformed.
    [[nodiscard]] std::uint64_t dropped() const { return dropped_; }
    /// Datagrams the emulated faults dropped, duplicated, reordered (both ways).
    [[nodiscard]] std::uint64_t emulated_losses() const { return emulated_losses_; }
    /// Snapshots given up with fragments missing.
    [[nodiscard]] std::uint64_t snapshots_incomplete() const { return assembler_.abandoned(); }
    /// When the kernel received the datagram being handled (inside on_envelope: the one
    /// that completed the envelope), on the steady clock; the time it was read where the
    /// kernel gave no timestamp.
    [[nodiscard]] std::chrono::steady_clock::time_point arrival() const { return arrival_; }

private:
    /// Opens the socket towards servers_[next_server_] (closing the one before), starts
    /// receiving and sends the request.
    bool open_next(std::string& error);
    /// open_next() on each address left in turn until one opens, as a TCP connect tries
    /// each (an IPv6 address first on a host without IPv6, say). False when none did:
    /// `error` then names each address tried and why it failed, joined by "; ". Each
    /// failure is also kept in tried_.
    bool open_next_that_opens(std::string& error);
    /// The link's address as "host:port" ("[host]:port" for IPv6).
    [[nodiscard]] std::string server_name() const;
    void receive_next();
    /// Reads every datagram waiting on the socket. False when the link no longer reads this
    /// socket (closed, moved to the next address, or given up: stop_reading()).
    bool drain();
    /// Tells the owner that the socket can no longer be read (Handlers::on_socket_error).
    void stop_reading(const std::string& why);
    void on_datagram(std::span<const std::uint8_t> datagram);
    void process(std::span<const std::uint8_t> datagram);
    void retry_handshake();
    void send(std::span<const std::uint8_t> datagram);
    void transmit(std::span<const std::uint8_t> datagram);
    [[nodiscard]] bool happens(double probability);

    Handlers handlers_;
    /// The owner. The handshake's retry timer holds it alive while it waits (the wait ends
    /// on its own); the receive wait, which lasts until the socket closes, holds it weakly
    /// (a strong hold would be a cycle through the socket) and does nothing once it is gone.
    std::weak_ptr<void> owner_;
    boost::asio::ip::udp::socket socket_;
    boost::asio::steady_timer retry_timer_;
    std::vector<boost::asio::ip::udp::endpoint> servers_;
    std::size_t next_server_ = 0; ///< the address to try when this one refuses
    /// What became of each address given up so far (refused, or could not be opened),
    /// for Handlers::on_refused.
    std::vector<std::string> tried_;
    bool refusal_reported_ = false; ///< on_refused was called: later refusals are ignored
    boost::asio::ip::udp::endpoint server_;
    boost::asio::ip::udp::endpoint sender_;
    /// drain()'s buffers: up to kReadBatch datagrams a system call, each one byte over the
    /// largest datagram, so that an oversized one is seen as such.
    static constexpr std::size_t kReadBatch = 8;
    std::array<std::array<std::uint8_t, protocol::kMaxDatagramBytes + 1>, kReadBatch> buffers_{};
    std::array<StampedRead, kReadBatch> reads_{};
    std::vector<std::uint8_t> datagram_;
    std::vector<std::uint8_t> request_;
    std::vector<std::uint8_t> response_;
    std::uint64_t nonce_ = 0;
    std::uint64_t session_ = 0;
    std::uint32_t next_sequence_ = 1;
    protocol::ReplayWindow window_;
    protocol::SnapshotAssembler assembler_;
    std::vector<protocol::pb::ClientInput> recent_inputs_; ///< the newest first, at most 3
    DatagramFaults faults_;
    std::vector<std::uint8_t> held_out_; ///< a sent datagram held back (reorder), or empty
    std::vector<std::uint8_t> held_in_;  ///< a received datagram held back, or empty
    std::mt19937_64 rng_;
    std::chrono::steady_clock::time_point arrival_{};
    std::uint64_t dropped_ = 0;
    std::uint64_t emulated_losses_ = 0;
    bool closed_ = false;
};

} // namespace dsoc::simclient
