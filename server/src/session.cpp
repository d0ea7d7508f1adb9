#include "dsoc/server/session.hpp"

#include "dsoc/protocol/codec.hpp"

#include <boost/asio/buffer.hpp>
#include <boost/asio/write.hpp>

#include <algorithm>
#include <limits>

#include <sys/socket.h>

namespace dsoc::server {

namespace asio = boost::asio;
namespace pb = protocol::pb;

namespace {

constexpr auto kCloseGrace = std::chrono::seconds(1);
constexpr std::size_t kKernelSlack = 16 * 1024; ///< [Units: bytes]
/// The first block of a thread's decoding arena: a client's messages (inputs, pings,
/// a hello with its token) are small. [Units: bytes]
constexpr std::size_t kIncomingArenaBytes = 4 * 1024;

std::string body_name(const pb::Envelope& message) {
    const auto* field = pb::Envelope::descriptor()->FindFieldByNumber(message.body_case());
    return field != nullptr ? field->name() : "nothing";
}

} // namespace

Session::Session(asio::ip::tcp::socket socket, std::uint32_t client_id, const ServerConfig& config,
                 ConnectionHost& host)
    : Connection(client_id, config.max_inputs_per_second, host), socket_(std::move(socket)),
      deadline_(socket_.get_executor()), config_(config), decoder_(config.max_frame_bytes) {
    boost::system::error_code ec;
    const auto endpoint = socket_.remote_endpoint(ec);
    remote_ =
        ec ? "unknown" : endpoint.address().to_string() + ":" + std::to_string(endpoint.port());
    if (!ec) {
        source_ = source_key(endpoint.address());
    }
    socket_.set_option(asio::ip::tcp::no_delay(true), ec);
    if (config_.socket_send_buffer_bytes > 0) {
        socket_.set_option(asio::socket_base::send_buffer_size(config_.socket_send_buffer_bytes),
                           ec);
    }
}

void Session::start() {
    await_hello(std::chrono::milliseconds(config_.handshake_timeout_ms));
    read_some();
}

void Session::await_hello(std::chrono::milliseconds within) {
    deadline_.expires_after(within); // a wait already set ends with operation_aborted
    deadline_.async_wait([self = self(), within](const boost::system::error_code& ec) {
        if (!ec && self->state_ == State::awaiting_hello) {
            self->disconnect(pb::DISCONNECT_REASON_HANDSHAKE_TIMEOUT,
                             "no client_hello within " + std::to_string(within.count()) + " ms");
        }
    });
}

void Session::hurry_hello(std::chrono::milliseconds within) {
    if (state_ == State::awaiting_hello && deadline_.expiry() - Clock::now() > within) {
        await_hello(within);
    }
}

void Session::read_some() {
    socket_.async_read_some(asio::buffer(read_buffer_),
                            [self = self()](const boost::system::error_code& ec, std::size_t n) {
                                if (self->state_ == State::closed) {
                                    return;
                                }
                                if (ec) {
                                    if (self->close_reason_ == pb::DISCONNECT_REASON_UNSPECIFIED) {
                                        self->close_reason_ = pb::DISCONNECT_REASON_CLIENT_QUIT;
                                    }
                                    self->close_now();
                                    return;
                                }
                                self->on_read(n);
                            });
}

void Session::on_read(std::size_t bytes) {
    receive(std::span<const std::uint8_t>(read_buffer_.data(), bytes));
    // While closing, keep draining until the peer closes, so our last frames are not reset.
    if (state_ != State::closed) {
        read_some();
    }
}

void Session::receive(std::span<const std::uint8_t> bytes) {
    bytes_received_ += bytes.size();
    if (state_ != State::awaiting_hello && state_ != State::active) {
        return;
    }
    decoder_.feed(bytes);
    while (state_ == State::awaiting_hello || state_ == State::active) {
        std::span<const std::uint8_t> payload;
        const auto status = decoder_.next(payload);
        if (status == protocol::FrameDecoder::Status::need_more) {
            break;
        }
        if (status == protocol::FrameDecoder::Status::too_large) {
            disconnect(pb::DISCONNECT_REASON_FRAME_TOO_LARGE,
                       "frame announces " + std::to_string(decoder_.rejected_length()) +
                           " bytes; the limit is " + std::to_string(config_.max_frame_bytes));
            break;
        }
        // Each message is handled before the next is decoded (handle() copies what it
        // keeps), so one arena per thread serves every session it reads for.
        thread_local protocol::EnvelopeArena incoming(kIncomingArenaBytes);
        const pb::Envelope* message = nullptr;
        const auto error = incoming.decode(payload, message);
        if (error != protocol::DecodeError::none) {
            disconnect(pb::DISCONNECT_REASON_PROTOCOL_ERROR,
                       std::string("frame of ") + std::to_string(payload.size()) +
                           " bytes: " + protocol::to_string(error) + " envelope");
            break;
        }
        handle(*message);
    }
}

void Session::handle(const pb::Envelope& message) {
    if (state_ == State::awaiting_hello) {
        if (message.body_case() != pb::Envelope::kClientHello) {
            disconnect(pb::DISCONNECT_REASON_PROTOCOL_ERROR,
                       "expected client_hello first, got " + body_name(message));
            return;
        }
        handle_hello(message.client_hello());
        return;
    }
    switch (message.body_case()) {
    case pb::Envelope::kClientInput:
    case pb::Envelope::kPing:
        handle_client_message(message);
        return;
    case pb::Envelope::kDisconnect:
        close_reason_ = pb::DISCONNECT_REASON_CLIENT_QUIT;
        state_ = State::closing;
        deadline_.expires_after(kCloseGrace);
        deadline_.async_wait([self = self()](const boost::system::error_code& ec) {
            if (!ec) {
                self->close_now();
            }
        });
        if (!writing_ && write_queue_.empty()) {
            boost::system::error_code ec;
            socket_.shutdown(asio::ip::tcp::socket::shutdown_send, ec);
        }
        return;
    default:
        disconnect(pb::DISCONNECT_REASON_PROTOCOL_ERROR,
                   "unexpected " + body_name(message) + " from a client");
        return;
    }
}

void Session::handle_client_message(const pb::Envelope& message) {
    if (!admit_message()) {
        return;
    }
    if (message.has_ping()) {
        send(pong_for(message.ping()));
    } else {
        deliver_input(message.client_input());
    }
}

void Session::handle_hello(const pb::ClientHello& hello) {
    if (!accept_hello(hello)) {
        return;
    }
    host_.on_hello(*this, hello);
    if (state_ == State::active) {
        deadline_.cancel();
    }
}

void Session::send(const pb::Envelope& message) {
    if (state_ != State::awaiting_hello && state_ != State::active) {
        return;
    }
    std::vector<std::uint8_t> frame;
    protocol::encode_frame(message, frame);
    if (queued_bytes_ + frame.size() > config_.max_send_queue_bytes) {
        disconnect(pb::DISCONNECT_REASON_TOO_SLOW,
                   "send queue holds " + std::to_string(queued_bytes_) +
                       " unsent bytes; the limit is " +
                       std::to_string(config_.max_send_queue_bytes));
        return;
    }
    enqueue(std::move(frame), false);
}

bool Session::offer_snapshot(Clock::time_point now, std::uint64_t /*tick*/) {
    if (state_ != State::active) {
        return false;
    }
    if (!snapshot_queued_) {
        return true;
    }
    ++snapshots_dropped_;
    const auto waited = now - snapshot_queued_at_;
    if (waited > std::chrono::milliseconds(config_.slow_client_timeout_ms)) {
        disconnect(pb::DISCONNECT_REASON_TOO_SLOW,
                   "a snapshot has waited " +
                       std::to_string(
                           std::chrono::duration_cast<std::chrono::milliseconds>(waited).count()) +
                       " ms to be sent (limit " + std::to_string(config_.slow_client_timeout_ms) +
                       " ms); " + std::to_string(snapshots_dropped_) +
                       " snapshots dropped so far: the client does not read fast enough");
    }
    return false;
}

void Session::send_snapshot(const pb::Envelope& message) {
    if (state_ != State::active || snapshot_queued_) {
        return;
    }
    std::vector<std::uint8_t> frame;
    protocol::encode_frame(message, frame);
    send_snapshot_frame(frame);
}

void Session::send_snapshot_frame(std::vector<std::uint8_t>& frame) {
    if (state_ != State::active || snapshot_queued_) {
        return;
    }
    if (queued_bytes_ + frame.size() > config_.max_send_queue_bytes) {
        disconnect(pb::DISCONNECT_REASON_TOO_SLOW,
                   "a snapshot of " + std::to_string(frame.size()) + " bytes on top of " +
                       std::to_string(queued_bytes_) + " unsent bytes exceeds the limit of " +
                       std::to_string(config_.max_send_queue_bytes));
        return;
    }
    snapshot_queued_ = true;
    snapshot_queued_at_ = Clock::now();
    std::vector<std::uint8_t> bytes;
    bytes.swap(frame);
    frame.swap(spare_frame_); // empty, with the capacity of an earlier snapshot
    frame.clear();
    enqueue(std::move(bytes), true);
}

bool Session::writable_now() const {
    return state_ == State::active && !snapshot_queued_ && !writing_ && write_queue_.empty();
}

std::size_t Session::write_now(std::span<const std::uint8_t> frame) noexcept {
    // Not through asio: the io thread, which owns the socket's asynchronous operations,
    // waits while this runs, and no write of ours is pending (writable_now()).
    const ssize_t n =
        ::send(socket_.native_handle(), frame.data(), frame.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    return n > 0 ? static_cast<std::size_t>(n) : 0;
}

bool Session::finish_write_now(std::vector<std::uint8_t>& frame, std::size_t written) {
    if (written == 0) {
        send_snapshot_frame(frame);
        return true;
    }
    bytes_sent_ += written;
    if (written >= frame.size()) {
        frame.clear();
        return false;
    }
    frame.erase(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(written));
    snapshot_queued_ = true;
    snapshot_queued_at_ = Clock::now();
    std::vector<std::uint8_t> rest;
    rest.swap(frame);
    frame.swap(spare_frame_);
    frame.clear();
    enqueue(std::move(rest), true);
    return true;
}

void Session::disconnect(pb::DisconnectReason reason, const std::string& text) {
    if (!begin_disconnect(reason, text)) {
        return;
    }
    state_ = State::closing;
    // The reason goes right after the frame being written (a frame cannot be cut):
    // everything queued behind that frame is dropped, stale snapshots included.
    const std::size_t in_flight = writing_ ? 1 : 0;
    while (write_queue_.size() > in_flight) {
        queued_bytes_ -= write_queue_.back().bytes.size();
        snapshot_queued_ = snapshot_queued_ && !write_queue_.back().snapshot;
        write_queue_.pop_back();
    }
    pb::Envelope message;
    message.mutable_disconnect()->set_reason(reason);
    message.mutable_disconnect()->set_text(text);
    std::vector<std::uint8_t> frame;
    protocol::encode_frame(message, frame);
    enqueue(std::move(frame), false); // beyond the queue limit on purpose: the reason must go out
    make_room_for_queue();
    deadline_.expires_after(kCloseGrace);
    deadline_.async_wait([self = self()](const boost::system::error_code& ec) {
        if (!ec) {
            self->close_now();
        }
    });
}

void Session::make_room_for_queue() {
    // A slow or stalled reader's kernel send buffer is full: grow it so that what is
    // left (the rest of one frame and the reason) is handed to the kernel at once.
    // The kernel delivers it whenever the client reads again, even after close_now()
    // (closing a socket does not discard what it still has to send), so the client
    // sees the reason, then end-of-file, however long it stalls before reading.
    boost::system::error_code ec;
    asio::socket_base::send_buffer_size current;
    socket_.get_option(current, ec);
    if (ec) {
        return;
    }
    // Twice what is queued: the kernel counts its bookkeeping against the buffer too.
    const std::size_t wanted =
        static_cast<std::size_t>(std::max(current.value(), 0)) + 2 * queued_bytes_ + kKernelSlack;
    socket_.set_option(asio::socket_base::send_buffer_size(static_cast<int>(
                           std::min<std::size_t>(wanted, std::numeric_limits<int>::max()))),
                       ec);
}

void Session::enqueue(std::vector<std::uint8_t> frame, bool snapshot) {
    queued_bytes_ += frame.size();
    peak_queued_bytes_ = std::max(peak_queued_bytes_, queued_bytes_);
    write_queue_.push_back({std::move(frame), snapshot});
    write_next();
}

void Session::write_next() {
    if (writing_ || write_queue_.empty() || state_ == State::closed) {
        return;
    }
    writing_ = true;
    asio::async_write(socket_, asio::buffer(write_queue_.front().bytes),
                      [self = self()](const boost::system::error_code& ec, std::size_t n) {
                          self->writing_ = false;
                          if (self->state_ == State::closed) {
                              return;
                          }
                          if (ec) {
                              self->close_now();
                              return;
                          }
                          self->bytes_sent_ += n;
                          self->queued_bytes_ -= self->write_queue_.front().bytes.size();
                          if (self->write_queue_.front().snapshot) {
                              self->snapshot_queued_ = false;
                              self->spare_frame_.swap(self->write_queue_.front().bytes);
                          }
                          self->write_queue_.pop_front();
                          if (!self->write_queue_.empty()) {
                              self->write_next();
                          } else if (self->state_ == State::closing) {
                              // Half-close: the peer reads our last frames, then closes.
                              boost::system::error_code ignored;
                              self->socket_.shutdown(asio::ip::tcp::socket::shutdown_send, ignored);
                          }
                      });
}

void Session::close_now() {
    if (state_ == State::closed) {
        return;
    }
    state_ = State::closed;
    deadline_.cancel();
    boost::system::error_code ec;
    socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ec);
    socket_.close(ec);
    write_queue_.clear();
    queued_bytes_ = 0;
    snapshot_queued_ = false;
    host_.on_closed(*this);
}

} // namespace dsoc::server
