#include "dsoc/server/connection.hpp"

#include "dsoc/protocol/codec.hpp"

#include <spdlog/spdlog.h>

namespace dsoc::server {

namespace pb = protocol::pb;

namespace {
constexpr std::size_t kMaxNameBytes = 64;
} // namespace

bool Connection::accept_hello(const pb::ClientHello& hello) {
    if (hello.protocol_version() != protocol::kProtocolVersion) {
        disconnect(pb::DISCONNECT_REASON_VERSION_MISMATCH,
                   "client speaks protocol " + std::to_string(hello.protocol_version()) +
                       ", server speaks " + std::to_string(protocol::kProtocolVersion));
        return false;
    }
    if (hello.name().size() > kMaxNameBytes) {
        disconnect(pb::DISCONNECT_REASON_INVALID_INPUT,
                   "client_hello.name is " + std::to_string(hello.name().size()) +
                       " bytes; at most " + std::to_string(kMaxNameBytes) + " allowed");
        return false;
    }
    name_ = hello.name();
    return true;
}

bool Connection::admit_message() {
    switch (limiter_.on_message(Clock::now())) {
    case InputRateLimiter::Decision::accept:
        return true;
    case InputRateLimiter::Decision::drop:
        return false;
    case InputRateLimiter::Decision::flood:
        disconnect(pb::DISCONNECT_REASON_INPUT_FLOOD,
                   "input flood: more than twice the cap of " +
                       std::to_string(static_cast<int>(limiter_.per_second())) +
                       " messages per second");
        return false;
    }
    return false;
}

bool Connection::deliver_input(const pb::ClientInput& input) {
    input_ = input;
    const InputVerdict verdict = sanitize_input(input_);
    if (!verdict.usable) {
        disconnect(pb::DISCONNECT_REASON_INVALID_INPUT, verdict.why);
        return false;
    }
    inputs_clamped_ += static_cast<std::uint64_t>(verdict.clamped_fields > 0);
    host_.on_input(*this, input_);
    return true;
}

bool Connection::begin_disconnect(pb::DisconnectReason reason, const std::string& text) {
    if (state_ == State::closing || state_ == State::closed) {
        return false;
    }
    spdlog::info("client {} ({}) disconnected: {}: {}", client_id_, remote_,
                 protocol::disconnect_reason_name(reason), text);
    close_reason_ = reason;
    return true;
}

pb::Envelope Connection::pong_for(const pb::Ping& ping) {
    pb::Envelope reply;
    auto& pong = *reply.mutable_pong();
    pong.set_nonce(ping.nonce());
    pong.set_client_time_us(ping.client_time_us());
    return reply;
}

} // namespace dsoc::server
