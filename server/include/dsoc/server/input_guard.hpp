#pragma once
// What the server does with a client's messages before the game sees them: input
// values are checked and clamped, and message rates are capped. Pure logic, no
// sockets, so that tests and fuzzers drive it directly.

#include "dsoc/protocol/messages.hpp"

#include <chrono>
#include <cstdint>
#include <string>

namespace dsoc::server {

struct InputVerdict {
    /// False: the input is unusable (a non-finite number) and the client is
    /// disconnected with invalid_input; `why` names the field.
    bool usable = true;
    /// Fields that were out of range and clamped (counted in the metrics): the
    /// movement length and the pitch. Wrapping the yaw is normalisation, not counted.
    int clamped_fields = 0;
    std::string why;
};

/// Checks `input` and clamps it in place: the movement intent to length <= 1, the
/// yaw wrapped to [-180, 180) degrees, the pitch clamped to [-90, 90] degrees. NaN
/// or infinity anywhere makes it unusable: there is no sensible value to clamp to,
/// and no honest client sends one.
[[nodiscard]] InputVerdict sanitize_input(protocol::pb::ClientInput& input);

/// Caps the messages one client may send: a token bucket of `per_second` tokens
/// refilled at `per_second` per second (a burst of one second's worth). A message
/// without a token is dropped; more than `per_second` drops within one second is a
/// flood. Not thread-safe; one per session.
class InputRateLimiter {
public:
    using Clock = std::chrono::steady_clock;
    enum class Decision : std::uint8_t {
        accept, ///< handle the message
        drop,   ///< over the cap: ignore this message
        flood,  ///< over the cap by more than the cap again: disconnect
    };

    /// `per_second` must be >= 1 (ServerConfig::max_inputs_per_second).
    InputRateLimiter(int per_second, Clock::time_point now);

    [[nodiscard]] Decision on_message(Clock::time_point now);

    [[nodiscard]] std::uint64_t dropped() const { return dropped_total_; }
    [[nodiscard]] double per_second() const { return per_second_; }

private:
    double per_second_;
    double tokens_;
    Clock::time_point last_refill_;
    Clock::time_point window_start_;
    std::uint64_t drops_in_window_ = 0;
    std::uint64_t dropped_total_ = 0;
};

} // namespace dsoc::server
