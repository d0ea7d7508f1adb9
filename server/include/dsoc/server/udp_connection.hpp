#pragma once
// One client's UDP session (docs/protocol.md, "UDP transport"): created by the
// UdpEndpoint once the client's response carried a valid cookie, so its address is
// proven; from then on it takes the client's datagrams the endpoint routes to it (by
// session id, from that address only, sequence numbers never taken before) and sends the
// hello reply, pongs, its disconnect and its snapshots as datagrams.
//
// Snapshots are acknowledged deltas (protocol/acked_snapshot.hpp): every input datagram
// carries the newest snapshot tick the client applied, and the server codes the next
// snapshot against it. Nothing is queued or retransmitted: a snapshot the kernel does not
// take, or the network loses, is simply replaced by the next one.
//
// Threading: as Connection; write_now() may run on a pool thread while the io thread
// waits (it sends on the endpoint's socket, which the kernel lets several threads use).

#include "dsoc/protocol/datagram.hpp"
#include "dsoc/protocol/update_columns.hpp"
#include "dsoc/server/connection.hpp"
#include "dsoc/server/server_config.hpp"
#include "dsoc/server/snapshot_pacer.hpp"

#include <boost/asio/ip/udp.hpp>

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::server {

class UdpEndpoint;

class UdpConnection final : public Connection {
public:
    /// `session`: the id the server assigned; `nonce`: the client's, from its request;
    /// `peer`: its proven address.
    UdpConnection(UdpEndpoint& endpoint, std::uint32_t client_id, std::uint64_t session,
                  std::uint64_t nonce, const boost::asio::ip::udp::endpoint& peer,
                  const ServerConfig& config, ConnectionHost& host);

    [[nodiscard]] Transport transport() const override { return Transport::udp; }

    /// The hello of the client's response: the version and name checks, then the host.
    void hello(const protocol::pb::ClientHello& hello);

    /// Awaiting the hello: the reply goes out as the `accepted` datagram (kept, and sent
    /// again for a duplicate response); afterwards as a `message` datagram.
    void send(const protocol::pb::Envelope& message) override;
    /// True while active and the client's pace (SnapshotPacer, from the age of its newest
    /// acknowledgement) lets it have this tick's snapshot; nothing ever waits in a queue.
    [[nodiscard]] bool offer_snapshot(Clock::time_point now, std::uint64_t tick) override;
    void send_snapshot_frame(std::vector<std::uint8_t>& frame) override;
    /// A snapshot frame is snapshot_frame()'s form: the tick, then the serialized envelope.
    [[nodiscard]] bool writable_now() const override { return active(); }
    /// Splits the frame into snapshot datagrams and sends them (queue_now(), a batch of
    /// its own, finish_queued()); returns the bytes the kernel took. A snapshot the kernel did not
    /// take whole (a full socket buffer), or one too large for kMaxSnapshotFragments datagrams
    /// (warned once), is dropped: the client cannot assemble it, and its tick is never taken as an
    /// acknowledgement.
    [[nodiscard]] std::size_t write_now(std::span<const std::uint8_t> frame) noexcept override;
    bool finish_write_now(std::vector<std::uint8_t>& frame, std::size_t written) override;
    /// The frame's datagrams into `batch` (on the endpoint's socket): none for a frame
    /// too large or a session out of sequence numbers. True: this transport batches.
    bool queue_now(std::span<const std::uint8_t> frame, DatagramBatch& batch) noexcept override;
    [[nodiscard]] std::size_t finish_queued(const DatagramBatch& batch) noexcept override;
    /// Sends the Disconnect (twice, in case one is lost: no acknowledgement is awaited)
    /// and closes at once.
    void disconnect(protocol::pb::DisconnectReason reason, const std::string& text) override;
    [[nodiscard]] std::optional<std::uint64_t> acked_tick() const override { return acked_; }

    /// Called by the endpoint for each datagram of this session that passed the replay
    /// window: `kind` is message or input. Returns false when the body does not parse
    /// (the endpoint counts it as bad_body).
    [[nodiscard]] bool receive(protocol::DatagramKind kind, std::span<const std::uint8_t> body,
                               std::size_t datagram_bytes, Clock::time_point now);
    /// A second response with this session's nonce and a valid cookie: the accepted
    /// datagram was lost; send it again.
    void resend_accepted();
    /// Disconnects with timed_out when nothing was heard for the configured time.
    void check_timeout(Clock::time_point now);

    /// The replay window of the client's sequence numbers (the endpoint's check).
    [[nodiscard]] protocol::ReplayWindow& replay_window() { return window_; }
    [[nodiscard]] std::uint64_t session() const { return session_; }
    [[nodiscard]] std::uint64_t nonce() const { return nonce_; }
    [[nodiscard]] const boost::asio::ip::udp::endpoint& peer() const { return peer_; }
    /// Snapshot datagrams the kernel refused (their snapshots count as dropped).
    [[nodiscard]] std::uint64_t datagrams_refused() const { return datagrams_refused_; }
    /// Before this many datagrams a session is ended (reconnect): sequence numbers never
    /// wrap. A session at 60 Hz sending 8 datagrams a tick lasts over 90 days.
    static constexpr std::uint32_t kLastSequence = 0xffff0000u;
    [[nodiscard]] SnapshotPaceCounts snapshots_paced() const override {
        return {pacer_.skipped_lagging(), pacer_.skipped_behind()};
    }

private:
    [[nodiscard]] bool handle_message(std::span<const std::uint8_t> body);
    /// Whether `ack` names a snapshot whose datagrams all went to the kernel.
    [[nodiscard]] bool acked_by_client(std::uint64_t ack) const;
    void send_datagram(std::span<const std::uint8_t> datagram);
    void close_now();

    UdpEndpoint& endpoint_;
    const ServerConfig& config_;
    std::uint64_t session_;
    std::uint64_t nonce_;
    boost::asio::ip::udp::endpoint peer_;
    protocol::ReplayWindow window_;
    std::uint32_t next_sequence_ = 1;
    std::optional<std::uint64_t> acked_;
    SnapshotPacer pacer_;
    std::uint64_t newest_snapshot_tick_ = 0; ///< the newest snapshot the kernel took whole
    /// Bit i: every datagram of the snapshot of newest_snapshot_tick_ - i went to the
    /// kernel (only those may be acknowledged).
    std::uint64_t sent_ticks_ = 0;
    bool warned_oversized_ = false;
    bool oversized_ = false;         ///< queue_now() met a snapshot too large (pool thread)
    bool last_write_whole_ = false;  ///< finish_queued(): every datagram went (pool thread)
    std::uint64_t newest_input_ = 0; ///< ClientInput.tick of the newest input taken
    Clock::time_point last_heard_;
    std::vector<std::uint8_t> accepted_; ///< the accepted datagram, for a duplicate response
    std::vector<std::uint8_t> datagram_; ///< scratch of the io thread
    std::vector<std::uint8_t> packed_;   ///< queue_now()'s datagrams, until finish_queued()
    /// queue_now()'s datagrams in its batch: the first's index, how many, and the tick.
    std::size_t batch_first_ = 0;
    std::size_t batch_count_ = 0;
    std::uint64_t batch_tick_ = 0;
    std::uint64_t datagrams_refused_ = 0;
};

/// The frame the server's job builds for a UDP client: the snapshot's tick (u64
/// little-endian), then the serialized envelope (clears `frame` first). `columns`: the
/// snapshot's update entries when they were built in wire form (null: in `envelope`).
void snapshot_frame(std::uint64_t tick, protocol::pb::Envelope& envelope,
                    const protocol::UpdateColumns* columns, std::vector<std::uint8_t>& frame);

} // namespace dsoc::server
