#include "dsoc/simclient/sim_client.hpp"

#include "dsoc/protocol/codec.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/write.hpp>

#include <algorithm>
#include <cmath>

namespace dsoc::simclient {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using Clock = std::chrono::steady_clock;

namespace {
constexpr float kPi = 3.14159265358979f;
constexpr auto kCloseGrace = std::chrono::seconds(2);

double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}
} // namespace

SimClient::SimClient(asio::io_context& io, const LoadConfig& config, int index)
    : io_(io), config_(config), index_(index), socket_(io), input_timer_(io), close_timer_(io),
      decoder_(config.max_frame_bytes),
      rng_(config.seed * 1'000'003ULL + static_cast<std::uint64_t>(index)) {}

void SimClient::start() {
    state_ = State::connecting;
    boost::system::error_code ec;
    const auto address = asio::ip::make_address(config_.host, ec);
    if (ec) {
        stats_.connect_failed = true;
        error("bad_server_address");
        state_ = State::closed;
        return;
    }
    const asio::ip::tcp::endpoint endpoint(address, config_.port);
    socket_.async_connect(endpoint,
                          [self = shared_from_this()](const boost::system::error_code& e) {
                              if (e) {
                                  self->stats_.connect_failed = true;
                                  self->state_ = State::closed;
                                  return;
                              }
                              self->on_connected();
                          });
}

void SimClient::on_connected() {
    boost::system::error_code ec;
    socket_.set_option(asio::ip::tcp::no_delay(true), ec);
    state_ = State::awaiting_hello;
    pb::Envelope hello;
    hello.mutable_client_hello()->set_protocol_version(protocol::kProtocolVersion);
    hello.mutable_client_hello()->set_name(config_.name_prefix + std::to_string(index_));
    if (config_.token_key) {
        const protocol::ConnectToken grant{config_.client_id_base +
                                               static_cast<std::uint64_t>(index_),
                                           protocol::unix_now_s() + config_.token_ttl_s};
        const auto token = protocol::mint_connect_token(*config_.token_key, grant);
        hello.mutable_client_hello()->set_connect_token(token.data(), token.size());
    } else if (!config_.connect_token.empty()) {
        hello.mutable_client_hello()->set_connect_token(config_.connect_token.data(),
                                                        config_.connect_token.size());
    }
    hello.mutable_client_hello()->set_audit_every_ticks(config_.audit_every_ticks);
    send(hello);
    read_some();
}

void SimClient::read_some() {
    socket_.async_read_some(asio::buffer(read_buffer_), [self = shared_from_this()](
                                                            const boost::system::error_code& ec,
                                                            std::size_t n) {
        if (self->state_ == State::closed) {
            return;
        }
        if (ec) {
            if (self->state_ != State::stopping && self->stats_.disconnect_reason.empty()) {
                self->stats_.unexpected_disconnect = true;
                self->stats_.disconnect_reason = "connection_lost";
                self->stats_.disconnect_text = ec.message();
            }
            self->close();
            return;
        }
        self->stats_.bytes_down += n;
        self->decoder_.feed(std::span<const std::uint8_t>(self->read_buffer_.data(), n));
        for (;;) {
            std::span<const std::uint8_t> payload;
            const auto status = self->decoder_.next(payload);
            if (status == protocol::FrameDecoder::Status::need_more) {
                break;
            }
            if (status == protocol::FrameDecoder::Status::too_large) {
                self->error("frame_too_large");
                self->close();
                return;
            }
            if (protocol::decode_payload(payload, self->incoming_) != protocol::DecodeError::none) {
                self->error("undecodable_message");
                continue;
            }
            self->handle(self->incoming_);
        }
        self->read_some();
    });
}

void SimClient::handle(const pb::Envelope& message) {
    switch (message.body_case()) {
    case pb::Envelope::kServerHello: {
        if (state_ == State::stopping && !stats_.hello_received) {
            return; // the run ended before the server answered: a connect failure, not a
                    // protocol error
        }
        if (state_ != State::awaiting_hello) {
            error("duplicate_server_hello");
            return;
        }
        const auto& hello = message.server_hello();
        stats_.hello_received = true;
        stats_.entity_id = hello.entity_id();
        tick_rate_ = hello.tick_rate() > 0 ? static_cast<int>(hello.tick_rate()) : 30;
        protocol::QuantizationSettings quantization;
        std::string why;
        if (!protocol::from_message(hello.quantization(), quantization, why)) {
            error("bad_quantization");
        }
        replica_.set_settings(quantization);
        state_ = State::active;
        active_since_ = Clock::now();
        next_input_at_ = active_since_;
        schedule_input();
        return;
    }
    case pb::Envelope::kSnapshot:
        if (state_ == State::awaiting_hello) {
            error("snapshot_before_hello");
            return;
        }
        apply_snapshot(message.snapshot());
        return;
    case pb::Envelope::kPong: {
        const auto now_us =
            std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
                .count();
        stats_.rtt_ms.add(static_cast<double>(
                              now_us - static_cast<std::int64_t>(message.pong().client_time_us())) /
                          1000.0);
        return;
    }
    case pb::Envelope::kDisconnect:
        stats_.disconnect_reason = protocol::disconnect_reason_name(message.disconnect().reason());
        stats_.disconnect_text = message.disconnect().text();
        if (message.disconnect().reason() != pb::DISCONNECT_REASON_SERVER_SHUTDOWN &&
            state_ != State::stopping) {
            stats_.unexpected_disconnect = true;
        }
        return;
    default:
        error("unexpected_message");
        return;
    }
}

void SimClient::apply_snapshot(const pb::Snapshot& s) {
    const auto now = Clock::now();
    if (stats_.snapshots > 0) {
        if (s.server_tick() <= last_snapshot_tick_) {
            error("snapshot_tick_not_increasing");
        }
        stats_.interarrival_ms.add(ms_between(last_snapshot_at_, now));
    }
    last_snapshot_tick_ = s.server_tick();
    last_snapshot_at_ = now;
    ++stats_.snapshots;
    for (const auto& problem : replica_.apply(s)) {
        error(problem.kind);
    }
    if (s.audit_size() > 0) {
        double worst = 0.0;
        for (const auto& problem : replica_.check_audit(s, worst)) {
            error(problem.kind);
        }
        stats_.audited_poses += static_cast<std::uint64_t>(s.audit_size());
        stats_.max_audit_error = std::max(stats_.max_audit_error, worst);
    }
    stats_.entity_updates += static_cast<std::uint64_t>(s.enter_size() + s.update_id_size());
    if (replica_.knows(stats_.entity_id)) {
        stats_.saw_own_entity = true;
    }
    stats_.known_samples.add(static_cast<double>(replica_.size()));
}

void SimClient::schedule_input() {
    next_input_at_ += std::chrono::nanoseconds(1'000'000'000LL / tick_rate_);
    input_timer_.expires_at(next_input_at_);
    input_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
        if (ec || self->state_ != State::active) {
            return;
        }
        self->send_input();
        self->schedule_input();
    });
}

void SimClient::send_input() {
    // Wander: hold a heading for 1-3 s, then pick another.
    if (--ticks_until_turn_ <= 0) {
        std::uniform_real_distribution<float> yaw(-180.0f, 180.0f);
        std::uniform_int_distribution<int> hold(tick_rate_, 3 * tick_rate_);
        wish_yaw_deg_ = yaw(rng_);
        ticks_until_turn_ = hold(rng_);
    }
    pb::Envelope message;
    auto& input = *message.mutable_client_input();
    input.set_tick(++input_seq_);
    input.set_move_x(std::cos(wish_yaw_deg_ * kPi / 180.0f));
    input.set_move_y(std::sin(wish_yaw_deg_ * kPi / 180.0f));
    input.set_view_yaw(wish_yaw_deg_);
    protocol::encode_frame(message, pending_);
    if (input_seq_ % static_cast<std::uint64_t>(tick_rate_) == 0) {
        pb::Envelope ping;
        ping.mutable_ping()->set_nonce(input_seq_);
        ping.mutable_ping()->set_client_time_us(static_cast<std::uint64_t>(
            std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
                .count()));
        protocol::encode_frame(ping, pending_); // same write as the input
    }
    write_next();
}

void SimClient::send(const pb::Envelope& message) {
    // Frames queued while a write is in flight go out together in the next write:
    // one send() per batch, and no allocation once the two buffers have grown.
    protocol::encode_frame(message, pending_);
    write_next();
}

void SimClient::write_next() {
    if (writing_ || pending_.empty() || state_ == State::closed) {
        return;
    }
    writing_ = true;
    in_flight_.swap(pending_);
    asio::async_write(
        socket_, asio::buffer(in_flight_),
        [self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
            self->writing_ = false;
            if (ec || self->state_ == State::closed) {
                return; // the read side reports the loss
            }
            self->stats_.bytes_up += n;
            self->in_flight_.clear();
            if (!self->pending_.empty()) {
                self->write_next();
            } else if (self->goodbye_sent_) {
                boost::system::error_code ignored;
                self->socket_.shutdown(asio::ip::tcp::socket::shutdown_send, ignored);
            }
        });
}

void SimClient::stop() {
    if (state_ == State::closed || state_ == State::stopping) {
        return;
    }
    if (state_ == State::active) {
        stats_.active_seconds = ms_between(active_since_, Clock::now()) / 1000.0;
    }
    const bool can_say_goodbye = state_ == State::active || state_ == State::awaiting_hello;
    state_ = State::stopping;
    input_timer_.cancel();
    if (can_say_goodbye && stats_.disconnect_reason.empty()) {
        pb::Envelope bye;
        bye.mutable_disconnect()->set_reason(pb::DISCONNECT_REASON_CLIENT_QUIT);
        bye.mutable_disconnect()->set_text("load run finished");
        goodbye_sent_ = true;
        send(bye);
    }
    close_timer_.expires_after(kCloseGrace);
    close_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
        if (!ec) {
            self->close();
        }
    });
}

void SimClient::error(const std::string& kind) {
    ++stats_.protocol_errors[kind];
}

void SimClient::close() {
    if (state_ == State::closed) {
        return;
    }
    if (state_ == State::active) {
        stats_.active_seconds = ms_between(active_since_, Clock::now()) / 1000.0;
    }
    state_ = State::closed;
    input_timer_.cancel();
    close_timer_.cancel();
    boost::system::error_code ec;
    socket_.close(ec);
}

} // namespace dsoc::simclient
