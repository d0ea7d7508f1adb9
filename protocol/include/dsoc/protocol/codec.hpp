#pragma once
// Envelope <-> frame. Decoding outside bytes never throws and never trusts them:
// every failure comes back as a DecodeError with a readable reason.

#include "dsoc/protocol/messages.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace dsoc::protocol {

enum class DecodeError : std::uint8_t {
    none,
    malformed,      ///< the payload is not a valid serialized Envelope
    empty_envelope, ///< a valid Envelope with no message set (or one this build does not know)
};

/// Readable name, e.g. "malformed". Static storage.
const char* to_string(DecodeError error) noexcept;

/// Serializes `message` and appends it to `out` as one frame. Returns the number of
/// bytes appended (header included).
std::size_t encode_frame(const pb::Envelope& message, std::vector<std::uint8_t>& out);

/// Parses one frame payload into `message` (cleared first).
[[nodiscard]] DecodeError decode_payload(std::span<const std::uint8_t> payload,
                                         pb::Envelope& message);

/// Readable name of a disconnect reason without the enum prefix, e.g. "frame_too_large".
std::string disconnect_reason_name(pb::DisconnectReason reason);

} // namespace dsoc::protocol
