#pragma once
// Envelope <-> frame. Decoding outside bytes never throws and never trusts them:
// every failure comes back as a DecodeError with a readable reason.

#include "dsoc/protocol/messages.hpp"

#include <google/protobuf/arena.h>

#include <cstdint>
#include <memory>
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

/// Decodes frame payloads into a protobuf arena that is reset and reused for each one,
/// so a stream of snapshots costs no heap allocation per message (a plain Envelope
/// frees and re-allocates its message, and every repeated field's growth, each time).
/// Messages larger than the arena's first block spill into blocks freed at the next
/// decode(). One thread at a time.
class EnvelopeArena {
public:
    /// `first_block_bytes`: kept across decodes (at least a few hundred bytes).
    explicit EnvelopeArena(std::size_t first_block_bytes);
    EnvelopeArena(const EnvelopeArena&) = delete;
    EnvelopeArena& operator=(const EnvelopeArena&) = delete;

    /// Parses `payload`; on DecodeError::none `message` points at the envelope, valid
    /// until the next decode() or the arena's end (null otherwise).
    [[nodiscard]] DecodeError decode(std::span<const std::uint8_t> payload,
                                     const pb::Envelope*& message);

private:
    std::unique_ptr<char[]> first_block_;
    google::protobuf::Arena arena_;
};

/// Readable name of a disconnect reason without the enum prefix, e.g. "frame_too_large".
std::string disconnect_reason_name(pb::DisconnectReason reason);

} // namespace dsoc::protocol
