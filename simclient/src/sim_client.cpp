#include "dsoc/simclient/sim_client.hpp"

#include "dsoc/protocol/codec.hpp"
#include "dsoc/simclient/failure_reason.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <fmt/format.h>

#include <algorithm>

namespace dsoc::simclient {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using Clock = std::chrono::steady_clock;

namespace {
constexpr auto kCloseGrace = std::chrono::seconds(2);
/// A UDP client that hears nothing from the server this long gives up (the server's own
/// timeout, udp_timeout_ms, is 5 s by default).
constexpr auto kUdpSilence = std::chrono::seconds(5);

/// When an input due at `due` leaves: the next whole millisecond of the steady clock.
/// Clients whose inputs fall due within the same millisecond then share one wakeup of
/// this process (and their arrival one of the server's I/O thread): at most 1,000 a
/// second, where one timer per input woke it clients x tick rate times a second (15,000
/// for 500 clients at 30 Hz). Each client keeps its own phase within the tick, and the
/// delay, under 1 ms, is below the jitter of any network a game is played over.
Clock::time_point on_whole_millisecond(Clock::time_point due) {
    return std::chrono::ceil<std::chrono::milliseconds>(due);
}

/// The first block of a thread's decoding arena: a snapshot of every entity of a
/// large arena, audit poses included, fits.
constexpr std::size_t kIncomingArenaBytes = 256 * 1024;

double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}
} // namespace

SimClient::SimClient(asio::io_context& io, const LoadConfig& config, SessionSetup setup)
    : io_(io), config_(config), setup_(std::move(setup)), resolver_(io), socket_(io),
      input_timer_(io), close_timer_(io), connect_timer_(io), decoder_(config.max_frame_bytes),
      input_model_(setup_.group != nullptr ? setup_.group->behaviour : Behaviour::wanderer,
                   config.seed * 1'000'003ULL + setup_.session) {
    const bool spectator =
        setup_.group != nullptr && setup_.group->behaviour == Behaviour::spectator;
    stats_.checks_snapshots = setup_.checks_snapshots || spectator;
    if (setup_.group != nullptr && setup_.group->network.any()) {
        const auto& net = setup_.group->network;
        delay_out_.emplace(io, net.latency_ms, net.jitter_ms, config.seed ^ (setup_.session << 1));
        delay_in_.emplace(io, net.latency_ms, net.jitter_ms, config.seed ^ (setup_.session << 2));
    }
}

std::string SimClient::name() const {
    return config_.name_prefix + std::to_string(setup_.index);
}

void SimClient::start() {
    state_ = State::connecting;
    started_at_ = Clock::now();
    connect_timer_.expires_after(
        std::chrono::microseconds(static_cast<long>(setup_.connect_timeout_s * 1e6)));
    connect_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
        if (ec || !self->connecting()) {
            return;
        }
        self->stats_.connect_failed = true;
        self->fail(
            failure::timeout,
            fmt::format("no {} within {:g} s",
                        self->state_ == State::connecting ? "TCP connection" : "server hello",
                        self->setup_.connect_timeout_s));
        self->close();
    });
    resolver_.async_resolve(
        setup_.host, std::to_string(setup_.port),
        [self = shared_from_this()](const boost::system::error_code& ec,
                                    const asio::ip::tcp::resolver::results_type& endpoints) {
            if (self->state_ != State::connecting) {
                return;
            }
            if (ec) {
                self->stats_.connect_failed = true;
                self->fail(failure::of_connect_error(ec, true),
                           "resolve " + self->setup_.host + ": " + ec.message());
                self->close();
                return;
            }
            self->on_resolved(endpoints);
        });
}

void SimClient::on_resolved(const asio::ip::tcp::resolver::results_type& endpoints) {
    if (config_.transport == LoadConfig::Transport::udp) {
        connect_udp(endpoints);
        return;
    }
    asio::async_connect(socket_, endpoints,
                        [self = shared_from_this()](const boost::system::error_code& ec,
                                                    const asio::ip::tcp::endpoint&) {
                            if (self->state_ != State::connecting) {
                                return;
                            }
                            if (ec) {
                                self->stats_.connect_failed = true;
                                self->fail(failure::of_connect_error(ec, false),
                                           fmt::format("connect to {}:{}: {}", self->setup_.host,
                                                       self->setup_.port, ec.message()));
                                self->close();
                                return;
                            }
                            self->on_connected();
                        });
}

void SimClient::on_connected() {
    boost::system::error_code ec;
    socket_.set_option(asio::ip::tcp::no_delay(true), ec);
    state_ = State::awaiting_hello;
    send(make_hello());
    read_some();
}

pb::Envelope SimClient::make_hello() const {
    pb::Envelope hello;
    hello.mutable_client_hello()->set_protocol_version(config_.protocol_version);
    hello.mutable_client_hello()->set_name(name());
    if (config_.token_key) {
        const protocol::ConnectToken grant{config_.client_id_base +
                                               static_cast<std::uint64_t>(setup_.index),
                                           protocol::unix_now_s() + config_.token_ttl_s};
        const auto token = protocol::mint_connect_token(*config_.token_key, grant);
        hello.mutable_client_hello()->set_connect_token(token.data(), token.size());
    } else if (!config_.connect_token.empty()) {
        hello.mutable_client_hello()->set_connect_token(config_.connect_token.data(),
                                                        config_.connect_token.size());
    }
    hello.mutable_client_hello()->set_audit_every_ticks(config_.audit_every_ticks);
    return hello;
}

void SimClient::connect_udp(const asio::ip::tcp::resolver::results_type& endpoints) {
    state_ = State::awaiting_hello;
    std::weak_ptr<SimClient> weak = weak_from_this();
    UdpLink::Handlers handlers;
    handlers.on_envelope = [weak](const pb::Envelope& message) {
        if (auto self = weak.lock()) {
            self->receive_udp(message);
        }
    };
    handlers.on_bytes_down = [weak](std::size_t n) {
        if (auto self = weak.lock()) {
            self->stats_.bytes_down += n;
        }
    };
    handlers.on_bytes_up = [weak](std::size_t n) {
        if (auto self = weak.lock()) {
            self->stats_.bytes_up += n;
        }
    };
    handlers.on_error = [weak](const std::string& kind) {
        if (auto self = weak.lock()) {
            self->error(kind);
        }
    };
    handlers.on_socket_error = [weak](const std::string& why) {
        if (auto self = weak.lock(); self && self->state_ != State::closed) {
            self->fail(failure::connection_lost, why);
            self->close();
        }
    };
    handlers.on_refused = [weak](const std::string& why) {
        if (auto self = weak.lock(); self && self->state_ != State::closed) {
            self->stats_.connect_failed = true;
            self->fail(failure::refused,
                       fmt::format("UDP to {}:{}: {}", self->setup_.host, self->setup_.port, why));
            self->close();
        }
    };
    const DatagramFaults faults = setup_.group != nullptr
                                      ? config_.udp_faults.worst_with(setup_.group->network.faults)
                                      : config_.udp_faults;
    udp_ = std::make_unique<UdpLink>(io_, std::move(handlers), faults,
                                     config_.seed ^ (setup_.session << 3));
    std::string why;
    std::vector<asio::ip::udp::endpoint> servers;
    for (const auto& entry : endpoints) {
        servers.emplace_back(entry.endpoint().address(), entry.endpoint().port());
    }
    if (!udp_->connect(std::move(servers), make_hello(), shared_from_this(), why)) {
        stats_.connect_failed = true;
        fail(failure::connection_lost, why);
        close();
    }
}

void SimClient::receive_udp(const pb::Envelope& message) {
    last_heard_ = Clock::now();
    if (!delay_in_) {
        arrival_ = udp_->arrival();
        handle(message);
        arrival_.reset();
        if (message.has_disconnect()) {
            close(); // the server has closed its side: there is no stream to end
        }
        return;
    }
    // Its arrival over the emulated link is when the delay line delivers it, known once
    // pushed: counted from the datagram's arrival at the socket, not from this moment.
    auto arrival = std::make_shared<Clock::time_point>();
    *arrival = delay_in_->push(
        [self = shared_from_this(), message, arrival] {
            if (self->state_ == State::closed) {
                return;
            }
            self->arrival_ = *arrival;
            self->handle(message);
            self->arrival_.reset();
            if (message.has_disconnect()) {
                self->close();
            }
        },
        shared_from_this(), udp_->arrival());
}

void SimClient::send_udp(const pb::Envelope& message) {
    if (state_ == State::closed) {
        return;
    }
    if (message.has_client_input()) {
        udp_->send_input(message.client_input(), acknowledged_tick());
    } else {
        udp_->send_message(message);
        if (message.has_disconnect()) {
            udp_->send_message(message); // nothing acknowledges it: twice, as the server does
        }
    }
}

void SimClient::read_some() {
    socket_.async_read_some(
        asio::buffer(read_buffer_),
        [self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
            if (self->state_ == State::closed) {
                return;
            }
            if (!ec) {
                self->stats_.bytes_down += n;
            }
            if (!self->delay_in_) {
                if (ec) {
                    self->on_read_error(ec);
                    return;
                }
                self->consume(std::span<const std::uint8_t>(self->read_buffer_.data(), n));
            } else if (ec) {
                // The end of the stream arrives after the bytes before it.
                self->delay_in_->push([self, ec] { self->on_read_error(ec); }, self);
                return;
            } else {
                std::vector<std::uint8_t> bytes(self->read_buffer_.begin(),
                                                self->read_buffer_.begin() + static_cast<long>(n));
                self->delay_in_->push(
                    [self, bytes = std::move(bytes)] {
                        self->consume(std::span<const std::uint8_t>(bytes));
                    },
                    self);
            }
            if (self->state_ != State::closed) {
                self->read_some();
            }
        });
}

void SimClient::on_read_error(const boost::system::error_code& ec) {
    if (state_ == State::closed) {
        return;
    }
    if (state_ != State::stopping && stats_.disconnect_reason.empty()) {
        stats_.unexpected_disconnect = true;
        stats_.connect_failed = !stats_.hello_received;
        stats_.disconnect_reason = "connection_lost";
        stats_.disconnect_text = ec.message();
        fail(failure::connection_lost, "connection closed without a reason: " + ec.message());
    }
    close();
}

void SimClient::consume(std::span<const std::uint8_t> bytes) {
    if (state_ == State::closed) {
        return;
    }
    decoder_.feed(bytes);
    for (;;) {
        std::span<const std::uint8_t> payload;
        const auto status = decoder_.next(payload);
        if (status == protocol::FrameDecoder::Status::need_more) {
            return;
        }
        if (status == protocol::FrameDecoder::Status::too_large) {
            error("frame_too_large");
            close();
            return;
        }
        // Each message is handled before the next is decoded, so one arena per thread
        // serves every session the thread runs (a snapshot fits in its first block).
        thread_local protocol::EnvelopeArena incoming(kIncomingArenaBytes);
        const pb::Envelope* message = nullptr;
        if (incoming.decode(payload, message) != protocol::DecodeError::none) {
            error("undecodable_message");
            continue;
        }
        handle(*message);
    }
}

void SimClient::handle(const pb::Envelope& message) {
    switch (message.body_case()) {
    case pb::Envelope::kServerHello:
        on_server_hello(message.server_hello());
        return;
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
        on_disconnect(message.disconnect());
        return;
    default:
        error("unexpected_message");
        return;
    }
}

void SimClient::on_server_hello(const pb::ServerHello& hello) {
    if (state_ == State::stopping && !stats_.hello_received) {
        return; // the run ended before the server answered: cancelled, not a protocol error
    }
    if (state_ != State::awaiting_hello) {
        error("duplicate_server_hello");
        return;
    }
    connect_timer_.cancel();
    stats_.hello_received = true;
    stats_.entity_id = hello.entity_id();
    tick_rate_ = hello.tick_rate() > 0 ? static_cast<int>(hello.tick_rate()) : 30;
    protocol::QuantizationSettings quantization;
    std::string why;
    if (!protocol::from_message(hello.quantization(), quantization, why)) {
        error("bad_quantization");
    }
    replica_.set_settings(quantization);
    acked_replica_ = protocol::AckedSnapshotDecoder(quantization);
    state_ = State::active;
    active_since_ = Clock::now();
    stats_.connect_ms = ms_between(started_at_, active_since_);
    last_heard_ = active_since_;
    next_input_at_ = active_since_;
    schedule_input();
}

void SimClient::on_disconnect(const pb::Disconnect& disconnect) {
    stats_.disconnect_reason = protocol::disconnect_reason_name(disconnect.reason());
    stats_.disconnect_text = disconnect.text();
    const std::string_view reason = failure::of_disconnect(disconnect.reason());
    // The server's own reason names a drop; the other failures are named by it already.
    const std::string detail = reason == failure::dropped_by_server
                                   ? stats_.disconnect_reason + ": " + disconnect.text()
                                   : disconnect.text();
    if (reason == failure::server_shutdown) {
        // Expected once the scenario is over; before that, it ends the test early.
        if (Clock::now() < setup_.run_end) {
            fail(reason, detail);
        }
        return;
    }
    if (!reason.empty() && state_ != State::stopping) {
        stats_.unexpected_disconnect = true;
        stats_.connect_failed = !stats_.hello_received;
        fail(reason, detail);
    }
}

void SimClient::count_snapshot(const pb::Snapshot& s) {
    const auto now = Clock::now();
    if (stats_.snapshots > 0) {
        if (s.server_tick() <= last_snapshot_tick_) {
            error("snapshot_tick_not_increasing");
        }
        const double gap = ms_between(last_snapshot_at_, now);
        stats_.interarrival_ms.add(gap);
        if (setup_.on_interarrival) {
            setup_.on_interarrival(gap);
        }
    }
    if (arrival_) {
        // Arrivals are in order (the kernel's, or the delay line's due times); a
        // negative span is conversion noise of a microsecond, counted as 0 (the
        // histogram would drop it).
        stats_.handling_lag_ms.add(std::max(0.0, ms_between(*arrival_, now)));
        if (last_snapshot_arrival_) {
            stats_.socket_interarrival_ms.add(
                std::max(0.0, ms_between(*last_snapshot_arrival_, *arrival_)));
        }
        last_snapshot_arrival_ = arrival_;
    }
    last_snapshot_tick_ = s.server_tick();
    last_snapshot_at_ = now;
    ++stats_.snapshots;
    stats_.entity_updates += static_cast<std::uint64_t>(s.enter_size() + s.update_head_size());
}

template <typename Replica>
void SimClient::apply_and_audit(Replica& replica, const pb::Snapshot& s) {
    count_snapshot(s);
    for (const auto& problem : replica.apply(s)) {
        error(problem.kind);
    }
    if (s.audit_size() > 0) {
        double worst = 0.0;
        for (const auto& problem : replica.check_audit(s, worst)) {
            error(problem.kind);
        }
        stats_.audited_poses += static_cast<std::uint64_t>(s.audit_size());
        stats_.max_audit_error = std::max(stats_.max_audit_error, worst);
    }
}

void SimClient::apply_snapshot(const pb::Snapshot& s) {
    if (!stats_.checks_snapshots) {
        discard_snapshot(s);
        return;
    }
    if (udp_) {
        apply_acked_snapshot(s);
        return;
    }
    apply_and_audit(replica_, s);
    if (replica_.knows(stats_.entity_id)) {
        stats_.saw_own_entity = true;
    }
    if (setup_.checks_snapshots) {
        stats_.known_samples.add(static_cast<double>(replica_.size()));
        stats_.heard_samples.add(static_cast<double>(replica_.heard()));
    }
}

void SimClient::apply_acked_snapshot(const pb::Snapshot& s) {
    // A snapshot arrives whole or not at all (the link reassembles it); one older than the
    // newest applied never arrives (the link drops it), so every one here must apply.
    apply_and_audit(acked_replica_, s);
    if (acked_replica_.find(stats_.entity_id) != nullptr) {
        stats_.saw_own_entity = true;
    }
    if (const protocol::DeltaFrame* frame = acked_replica_.newest();
        frame != nullptr && setup_.checks_snapshots) {
        std::size_t heard = 0;
        for (const protocol::FrameEntity& e : frame->entities) {
            heard += e.tier == protocol::kHeardTier ? 1 : 0;
        }
        stats_.known_samples.add(static_cast<double>(frame->entities.size()));
        stats_.heard_samples.add(static_cast<double>(heard));
    }
    send_input_on_snapshot();
}

void SimClient::discard_snapshot(const pb::Snapshot& s) {
    count_snapshot(s);
    acked_unread_tick_ = std::max(acked_unread_tick_, s.server_tick());
    stats_.saw_own_entity =
        stats_.saw_own_entity ||
        std::any_of(s.enter().begin(), s.enter().end(),
                    [this](const pb::EntityState& e) { return e.id() == stats_.entity_id; });
    if (udp_) {
        send_input_on_snapshot();
    }
}

std::uint64_t SimClient::acknowledged_tick() const {
    return stats_.checks_snapshots ? acked_replica_.newest_tick().value_or(0) : acked_unread_tick_;
}

void SimClient::send_input_on_snapshot() {
    const auto now = Clock::now();
    const auto tick = tick_period();
    if (state_ != State::active || now - last_input_at_ < tick / 2) {
        return; // an input left less than half a tick ago
    }
    send_input();
    // The clock's next input a tick and a half from now: it stands in for a snapshot
    // lost or paced, and does not race one that comes a little late.
    next_input_at_ = now + tick / 2;
    schedule_input();
}

std::size_t SimClient::known() const {
    if (udp_) {
        const protocol::DeltaFrame* frame = acked_replica_.newest();
        return frame != nullptr ? frame->entities.size() : 0;
    }
    return replica_.size();
}

bool SimClient::knows(std::uint32_t id) const {
    return udp_ ? acked_replica_.find(id) != nullptr : replica_.knows(id);
}

void SimClient::players(std::vector<std::uint32_t>& out) const {
    constexpr std::uint32_t kPlayer = 1; // EntityState.kind
    if (udp_) {
        if (const protocol::DeltaFrame* frame = acked_replica_.newest()) {
            for (const protocol::FrameEntity& e : frame->entities) {
                if (e.kind == kPlayer) {
                    out.push_back(e.id);
                }
            }
        }
        return;
    }
    replica_.entities().for_each([&](std::uint32_t id, const protocol::ReplicaEntity& e) {
        if (e.kind == kPlayer) {
            out.push_back(id);
        }
    });
}

void SimClient::schedule_input() {
    next_input_at_ += tick_period();
    // A wait that already completed, its handler queued, is not cancelled by re-arming
    // the timer: the handler knows it is stale by this count.
    const std::uint64_t armed = ++input_clock_armed_;
    input_timer_.expires_at(on_whole_millisecond(next_input_at_));
    input_timer_.async_wait([self = shared_from_this(),
                             armed](const boost::system::error_code& ec) {
        if (ec || self->state_ != State::active || armed != self->input_clock_armed_) {
            return;
        }
        if (self->udp_ && Clock::now() - self->last_heard_ > kUdpSilence) {
            self->stats_.unexpected_disconnect = true;
            self->stats_.disconnect_reason = "connection_lost";
            self->fail(
                failure::connection_lost,
                fmt::format("nothing from the server over UDP for {} s",
                            std::chrono::duration_cast<std::chrono::seconds>(kUdpSilence).count()));
            self->close();
            return;
        }
        self->send_input();
        self->schedule_input();
    });
}

void SimClient::send_input() {
    last_input_at_ = Clock::now();
    pb::Envelope message;
    auto& input = *message.mutable_client_input();
    input.set_tick(++input_seq_);
    input_model_.next(input, tick_rate_, *this, stats_.entity_id);
    send(message);
    if (input_seq_ % static_cast<std::uint64_t>(tick_rate_) == 0) {
        pb::Envelope ping;
        ping.mutable_ping()->set_nonce(input_seq_);
        ping.mutable_ping()->set_client_time_us(static_cast<std::uint64_t>(
            std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
                .count()));
        send(ping); // same write as the input, when no write is in flight
    }
}

void SimClient::send(const pb::Envelope& message, bool goodbye) {
    if (udp_) {
        if (!delay_out_) {
            send_udp(message);
        } else {
            delay_out_->push([self = shared_from_this(), message] { self->send_udp(message); },
                             shared_from_this());
        }
        return;
    }
    if (!delay_out_) {
        // Frames queued while a write is in flight go out together in the next write:
        // one send() per batch, and no allocation once the two buffers have grown.
        protocol::encode_frame(message, pending_);
        goodbye_sent_ = goodbye_sent_ || goodbye;
        write_next();
        return;
    }
    frame_.clear();
    protocol::encode_frame(message, frame_);
    delay_out_->push(
        [self = shared_from_this(), frame = frame_, goodbye] { self->queue_frame(frame, goodbye); },
        shared_from_this());
}

void SimClient::queue_frame(std::span<const std::uint8_t> frame, bool goodbye) {
    if (state_ == State::closed) {
        return;
    }
    pending_.insert(pending_.end(), frame.begin(), frame.end());
    goodbye_sent_ = goodbye_sent_ || goodbye;
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
    if (state_ == State::idle || state_ == State::connecting) {
        close(); // nothing said yet: nothing to say goodbye to
        return;
    }
    if (state_ == State::active) {
        stats_.active_seconds = ms_between(active_since_, Clock::now()) / 1000.0;
    }
    state_ = State::stopping;
    input_timer_.cancel();
    connect_timer_.cancel();
    if (stats_.disconnect_reason.empty()) {
        pb::Envelope bye;
        bye.mutable_disconnect()->set_reason(pb::DISCONNECT_REASON_CLIENT_QUIT);
        bye.mutable_disconnect()->set_text("load run finished");
        send(bye, /*goodbye=*/true);
    }
    if (udp_ && !delay_out_) {
        close(); // over UDP nothing ends a stream: the goodbye has gone
        return;
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
    fail(failure::protocol_error, kind);
}

void SimClient::fail(std::string_view reason, const std::string& detail) {
    if (!stats_.failure.empty()) {
        return;
    }
    stats_.failure = std::string(reason);
    stats_.failure_detail = detail;
    if (setup_.on_failure) {
        asio::post(io_, [self = shared_from_this()] { self->setup_.on_failure(*self); });
    }
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
    connect_timer_.cancel();
    resolver_.cancel();
    if (delay_out_) {
        delay_out_->clear();
        delay_in_->clear();
    }
    boost::system::error_code ec;
    socket_.close(ec);
    if (udp_) {
        udp_->close();
    }
    if (setup_.on_closed) {
        asio::post(io_, [self = shared_from_this()] { self->setup_.on_closed(*self); });
    }
}

} // namespace dsoc::simclient
