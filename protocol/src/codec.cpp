#include "dsoc/protocol/codec.hpp"

#include "dsoc/protocol/framing.hpp"

namespace dsoc::protocol {

const char* to_string(DecodeError error) noexcept {
    switch (error) {
    case DecodeError::none:
        return "none";
    case DecodeError::malformed:
        return "malformed";
    case DecodeError::empty_envelope:
        return "empty_envelope";
    }
    return "unknown";
}

std::size_t encode_frame(const pb::Envelope& message, std::vector<std::uint8_t>& out) {
    const std::size_t payload = message.ByteSizeLong();
    const std::size_t start = out.size();
    out.resize(start + kFrameHeaderBytes + payload);
    write_frame_header(out.data() + start, static_cast<std::uint32_t>(payload));
    message.SerializeWithCachedSizesToArray(out.data() + start + kFrameHeaderBytes);
    return kFrameHeaderBytes + payload;
}

DecodeError decode_payload(std::span<const std::uint8_t> payload, pb::Envelope& message) {
    message.Clear();
    if (!message.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) {
        return DecodeError::malformed;
    }
    if (message.body_case() == pb::Envelope::BODY_NOT_SET) {
        return DecodeError::empty_envelope;
    }
    return DecodeError::none;
}

namespace {

google::protobuf::ArenaOptions first_block_options(char* block, std::size_t bytes) {
    google::protobuf::ArenaOptions options;
    options.initial_block = block;
    options.initial_block_size = bytes;
    return options;
}

} // namespace

EnvelopeArena::EnvelopeArena(std::size_t first_block_bytes)
    : first_block_(std::make_unique<char[]>(first_block_bytes)),
      arena_(first_block_options(first_block_.get(), first_block_bytes)) {}

DecodeError EnvelopeArena::decode(std::span<const std::uint8_t> payload,
                                  const pb::Envelope*& message) {
    message = nullptr;
    arena_.Reset(); // the previous message, and any block beyond the first
    auto* parsed = google::protobuf::Arena::CreateMessage<pb::Envelope>(&arena_);
    const DecodeError error = decode_payload(payload, *parsed);
    if (error == DecodeError::none) {
        message = parsed;
    }
    return error;
}

} // namespace dsoc::protocol
