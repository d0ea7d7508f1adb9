#include "dsoc/server/udp_connection.hpp"

#include "dsoc/server/datagram_batch.hpp"

#include "dsoc/protocol/buffer_room.hpp"
#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/delta_frame.hpp"
#include "dsoc/server/udp_endpoint.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>

#include <sys/socket.h>
#include <sys/uio.h>

namespace dsoc::server {

namespace pb = protocol::pb;
using protocol::DatagramKind;

namespace {

constexpr std::size_t kTickBytes = 8;
/// Room a snapshot's frame and datagram buffers keep beyond twice their last use
/// (protocol/buffer_room.hpp). [Units: bytes]
constexpr std::size_t kScratchSlackBytes = 4096;
/// The first block of a thread's decoding arena: a client's messages are small.
constexpr std::size_t kIncomingArenaBytes = 4 * 1024;

std::uint64_t get_u64(const std::uint8_t* in) {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < kTickBytes; ++i) {
        v |= static_cast<std::uint64_t>(in[i]) << (8 * i);
    }
    return v;
}

} // namespace

void snapshot_frame(std::uint64_t tick, pb::Envelope& envelope,
                    const protocol::UpdateColumns* columns, std::vector<std::uint8_t>& frame) {
    frame.clear();
    for (std::size_t i = 0; i < kTickBytes; ++i) {
        frame.push_back(static_cast<std::uint8_t>(tick >> (8 * i)));
    }
    if (columns != nullptr) {
        protocol::append_snapshot_envelope(envelope, *columns, frame);
        return;
    }
    const std::size_t size = envelope.ByteSizeLong();
    frame.resize(kTickBytes + size);
    envelope.SerializeToArray(frame.data() + kTickBytes, static_cast<int>(size));
}

UdpConnection::UdpConnection(UdpEndpoint& endpoint, std::uint32_t client_id, std::uint64_t session,
                             std::uint64_t nonce, const boost::asio::ip::udp::endpoint& peer,
                             const ServerConfig& config, ConnectionHost& host)
    : Connection(client_id, config.max_inputs_per_second, host), endpoint_(endpoint),
      config_(config), session_(session), nonce_(nonce), peer_(peer), pacer_(config.tick_rate),
      last_heard_(Clock::now()) {
    remote_ = "udp:" + peer.address().to_string() + ":" + std::to_string(peer.port());
    source_ = source_key(peer.address());
}

void UdpConnection::hello(const pb::ClientHello& hello) {
    if (accept_hello(hello)) {
        host_.on_hello(*this, hello);
    }
}

void UdpConnection::send(const pb::Envelope& message) {
    if (state_ == State::awaiting_hello) {
        std::array<std::uint8_t, 8> id{};
        for (std::size_t i = 0; i < id.size(); ++i) {
            id[i] = static_cast<std::uint8_t>(session_ >> (8 * i));
        }
        if (protocol::write_envelope_datagram({DatagramKind::accepted, nonce_, 0}, id, &message,
                                              accepted_)) {
            send_datagram(accepted_);
        }
        return;
    }
    if (state_ != State::active) {
        return;
    }
    if (protocol::write_envelope_datagram({DatagramKind::message, session_, next_sequence_}, {},
                                          &message, datagram_)) {
        ++next_sequence_;
        send_datagram(datagram_);
    } else {
        spdlog::warn("client {} ({}): a {}-byte message does not fit in one datagram; not sent",
                     client_id_, remote_, message.ByteSizeLong());
    }
}

void UdpConnection::resend_accepted() {
    if (!accepted_.empty()) {
        send_datagram(accepted_);
    }
}

bool UdpConnection::offer_snapshot(Clock::time_point, std::uint64_t tick) {
    if (!active()) {
        return false;
    }
    if (!pacer_.offer(tick, acked_)) {
        ++snapshots_dropped_;
        return false;
    }
    return true;
}

void UdpConnection::send_snapshot_frame(std::vector<std::uint8_t>& frame) {
    finish_write_now(frame, write_now(frame));
}

std::size_t UdpConnection::write_now(std::span<const std::uint8_t> frame) noexcept {
    thread_local DatagramBatch batch; // its memory kept from call to call
    batch.clear();
    queue_now(frame, batch);
    batch.send();
    return finish_queued(batch);
}

bool UdpConnection::queue_now(std::span<const std::uint8_t> frame, DatagramBatch& batch) noexcept {
    last_write_whole_ = false;
    batch_count_ = 0;
    if (frame.size() <= kTickBytes || next_sequence_ > kLastSequence) {
        return true;
    }
    const std::uint64_t tick = get_u64(frame.data());
    protocol::clear_to_need(packed_, kScratchSlackBytes);
    const std::size_t count = protocol::write_snapshot_datagrams(
        session_, next_sequence_, tick, frame.subspan(kTickBytes), packed_);
    if (count == 0) {
        oversized_ = true; // warned on the io thread (finish_write_now)
        return true;
    }
    next_sequence_ += static_cast<std::uint32_t>(count);
    batch_first_ = batch.size();
    batch_tick_ = tick;
    for (std::size_t at = 0; at + 2 <= packed_.size();) {
        const std::size_t size = packed_[at] | (static_cast<std::size_t>(packed_[at + 1]) << 8);
        batch.add(endpoint_.native_handle(), std::span(packed_.data() + at + 2, size), peer_.data(),
                  static_cast<socklen_t>(peer_.size()));
        at += 2 + size;
    }
    batch_count_ = batch.size() - batch_first_;
    return true;
}

std::size_t UdpConnection::finish_queued(const DatagramBatch& batch) noexcept {
    std::size_t sent = 0;
    std::size_t refused = 0;
    for (std::size_t i = batch_first_; i < batch_first_ + batch_count_; ++i) {
        sent += batch.sent_bytes(i);
        refused += batch.refused(i) ? 1 : 0;
    }
    datagrams_refused_ += refused;
    if (batch_count_ > 0 && refused == 0 && batch_tick_ > newest_snapshot_tick_) {
        const std::uint64_t shift = batch_tick_ - newest_snapshot_tick_;
        sent_ticks_ = (shift >= 64 ? 0 : sent_ticks_ << shift) | 1;
        newest_snapshot_tick_ = batch_tick_;
        last_write_whole_ = true;
    }
    batch_count_ = 0;
    return sent;
}

bool UdpConnection::finish_write_now(std::vector<std::uint8_t>& frame, std::size_t written) {
    bytes_sent_ += written;
    snapshots_dropped_ += last_write_whole_ ? 0 : 1;
    if (oversized_ && !warned_oversized_) {
        warned_oversized_ = true;
        spdlog::warn("client {} ({}): a snapshot of {} bytes is larger than {} datagrams carry "
                     "({} bytes); such snapshots are dropped",
                     client_id_, remote_, frame.size() - kTickBytes,
                     protocol::kMaxSnapshotFragments, protocol::kMaxSnapshotBytes);
    }
    oversized_ = false;
    protocol::clear_to_need(frame, kScratchSlackBytes);
    if (next_sequence_ > kLastSequence && state_ == State::active) {
        disconnect(protocol::pb::DISCONNECT_REASON_PROTOCOL_ERROR,
                   "the session has used its sequence numbers; reconnect");
    }
    return false;
}

void UdpConnection::disconnect(pb::DisconnectReason reason, const std::string& text) {
    if (!begin_disconnect(reason, text)) {
        return;
    }
    pb::Envelope message;
    message.mutable_disconnect()->set_reason(reason);
    message.mutable_disconnect()->set_text(text);
    if (state_ == State::awaiting_hello) {
        send(message); // as the accepted datagram: the client has no session yet
    } else {
        send(message);
        send(message);
    }
    close_now();
}

void UdpConnection::check_timeout(Clock::time_point now) {
    const auto silent = now - last_heard_;
    if (state_ == State::active && silent > std::chrono::milliseconds(config_.udp_timeout_ms)) {
        disconnect(pb::DISCONNECT_REASON_TIMED_OUT,
                   "nothing heard for " +
                       std::to_string(
                           std::chrono::duration_cast<std::chrono::milliseconds>(silent).count()) +
                       " ms (limit " + std::to_string(config_.udp_timeout_ms) + " ms)");
    }
}

bool UdpConnection::receive(DatagramKind kind, std::span<const std::uint8_t> body,
                            std::size_t datagram_bytes, Clock::time_point now) {
    if (state_ != State::active) {
        return true;
    }
    bytes_received_ += datagram_bytes;
    last_heard_ = now;
    if (kind == DatagramKind::message) {
        return handle_message(body);
    }
    // The rate cap counts datagrams (an honest client sends one a tick), whatever they
    // hold: redundant inputs already taken and bodies that do not parse cost a token too,
    // so the token is taken before the body is read.
    if (!admit_message()) {
        return true;
    }
    protocol::InputBody inputs;
    if (protocol::read_input_body(body, inputs) != protocol::DatagramError::none) {
        return false;
    }
    // Only an acknowledgement of a snapshot the kernel took whole counts: another one
    // would make the server code against a frame the client does not hold.
    if (acked_by_client(inputs.ack) && (!acked_ || inputs.ack > *acked_)) {
        acked_ = inputs.ack;
    }
    thread_local pb::ClientInput input;
    bool parsed_all = true;
    // The oldest first: each input newer than the newest taken goes to the host in order.
    for (std::size_t i = inputs.count; i-- > 0;) {
        if (!input.ParseFromArray(inputs.inputs[i].data(),
                                  static_cast<int>(inputs.inputs[i].size()))) {
            parsed_all = false;
            continue;
        }
        if (input.tick() <= newest_input_) {
            continue; // sent again for redundancy, already taken
        }
        newest_input_ = input.tick();
        if (!deliver_input(input)) {
            return true;
        }
    }
    return parsed_all;
}

bool UdpConnection::acked_by_client(std::uint64_t ack) const {
    return ack != 0 && ack <= newest_snapshot_tick_ && newest_snapshot_tick_ - ack < 64 &&
           ((sent_ticks_ >> (newest_snapshot_tick_ - ack)) & 1) != 0;
}

bool UdpConnection::handle_message(std::span<const std::uint8_t> body) {
    if (!admit_message()) {
        return true;
    }
    thread_local protocol::EnvelopeArena incoming(kIncomingArenaBytes);
    const pb::Envelope* message = nullptr;
    if (incoming.decode(body, message) != protocol::DecodeError::none) {
        return false;
    }
    switch (message->body_case()) {
    case pb::Envelope::kPing:
        send(pong_for(message->ping()));
        return true;
    case pb::Envelope::kDisconnect:
        close_reason_ = pb::DISCONNECT_REASON_CLIENT_QUIT;
        close_now();
        return true;
    default:
        return false; // nothing else is meaningful from a client in a message datagram
    }
}

void UdpConnection::send_datagram(std::span<const std::uint8_t> datagram) {
    if (endpoint_.send_to(peer_, datagram)) {
        bytes_sent_ += datagram.size();
    }
}

void UdpConnection::close_now() {
    if (state_ == State::closed) {
        return;
    }
    state_ = State::closed;
    endpoint_.forget(*this);
    host_.on_closed(*this);
}

} // namespace dsoc::server
