#include "dsoc/protocol/framing.hpp"

#include <cstring>

namespace dsoc::protocol {

void write_frame_header(std::uint8_t* header, std::uint32_t length) {
    header[0] = static_cast<std::uint8_t>(length & 0xffu);
    header[1] = static_cast<std::uint8_t>((length >> 8) & 0xffu);
    header[2] = static_cast<std::uint8_t>((length >> 16) & 0xffu);
    header[3] = static_cast<std::uint8_t>((length >> 24) & 0xffu);
}

void append_frame(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> payload) {
    const std::size_t start = out.size();
    out.resize(start + kFrameHeaderBytes + payload.size());
    write_frame_header(out.data() + start, static_cast<std::uint32_t>(payload.size()));
    if (!payload.empty()) {
        std::memcpy(out.data() + start + kFrameHeaderBytes, payload.data(), payload.size());
    }
}

FrameDecoder::FrameDecoder(std::uint32_t max_payload_bytes)
    : max_payload_bytes_(max_payload_bytes) {}

void FrameDecoder::feed(std::span<const std::uint8_t> bytes) {
    // Drop consumed bytes before growing, so the buffer holds at most one partial
    // frame plus the new piece.
    if (read_offset_ > 0) {
        buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(read_offset_));
        read_offset_ = 0;
    }
    buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
}

FrameDecoder::Status FrameDecoder::next(std::span<const std::uint8_t>& payload) {
    if (rejected_length_ != 0) {
        return Status::too_large;
    }
    const std::size_t available = buffer_.size() - read_offset_;
    if (available < kFrameHeaderBytes) {
        return Status::need_more;
    }
    const std::uint8_t* header = buffer_.data() + read_offset_;
    const std::uint32_t length = static_cast<std::uint32_t>(header[0]) |
                                 (static_cast<std::uint32_t>(header[1]) << 8) |
                                 (static_cast<std::uint32_t>(header[2]) << 16) |
                                 (static_cast<std::uint32_t>(header[3]) << 24);
    if (length > max_payload_bytes_) {
        rejected_length_ = length == 0 ? 1 : length;
        return Status::too_large;
    }
    if (available - kFrameHeaderBytes < length) {
        return Status::need_more;
    }
    payload = std::span<const std::uint8_t>(header + kFrameHeaderBytes, length);
    read_offset_ += kFrameHeaderBytes + length;
    return Status::frame;
}

} // namespace dsoc::protocol
