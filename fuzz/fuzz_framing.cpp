// Fuzzes TCP framing and envelope decoding: the bytes arrive in pieces whose sizes
// the input chooses; every frame the decoder returns is decoded as an Envelope,
// and a decoded Envelope must survive encode -> decode.

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/framing.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) {
        return 0;
    }
    // Byte 0: the largest piece fed at once (1..256); byte 1: the frame limit (in
    // 64-byte steps, so that too_large is reachable).
    const std::size_t piece = static_cast<std::size_t>(data[0]) + 1;
    const std::uint32_t limit = 64u * (static_cast<std::uint32_t>(data[1]) + 1u);
    dsoc::protocol::FrameDecoder decoder(limit);
    dsoc::protocol::pb::Envelope message;
    dsoc::protocol::pb::Envelope again;
    std::vector<std::uint8_t> frame;
    std::span<const std::uint8_t> rest(data + 2, size - 2);
    while (!rest.empty()) {
        const std::size_t n = std::min(piece, rest.size());
        decoder.feed(rest.first(n));
        rest = rest.subspan(n);
        if (decoder.buffered_bytes() > limit + dsoc::protocol::kFrameHeaderBytes + piece) {
            std::abort(); // the documented memory bound does not hold
        }
        for (;;) {
            std::span<const std::uint8_t> payload;
            const auto status = decoder.next(payload);
            if (status == dsoc::protocol::FrameDecoder::Status::too_large) {
                if (decoder.rejected_length() <= limit) {
                    std::abort();
                }
                return 0; // the stream is unusable from here
            }
            if (status == dsoc::protocol::FrameDecoder::Status::need_more) {
                break;
            }
            if (payload.size() > limit) {
                std::abort();
            }
            if (dsoc::protocol::decode_payload(payload, message) !=
                dsoc::protocol::DecodeError::none) {
                continue;
            }
            frame.clear();
            const std::size_t written = dsoc::protocol::encode_frame(message, frame);
            if (written != frame.size() || frame.size() < dsoc::protocol::kFrameHeaderBytes ||
                dsoc::protocol::decode_payload(
                    std::span<const std::uint8_t>(frame).subspan(dsoc::protocol::kFrameHeaderBytes),
                    again) != dsoc::protocol::DecodeError::none) {
                std::abort(); // something we decoded does not encode back
            }
        }
    }
    return 0;
}
