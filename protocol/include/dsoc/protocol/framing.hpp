#pragma once
// TCP framing: every message is a 4-byte little-endian payload length followed by
// that many payload bytes. The decoder accepts bytes in arbitrary pieces (a frame
// may arrive one byte at a time, or many frames in one read).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::protocol {

inline constexpr std::size_t kFrameHeaderBytes = 4;
/// Default largest payload a peer may send. [Units: bytes]
inline constexpr std::uint32_t kDefaultMaxFrameBytes = 64 * 1024;

/// Appends one frame (header + payload) to `out`.
void append_frame(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> payload);

/// Writes the 4-byte little-endian header for a payload of `length` bytes.
void write_frame_header(std::uint8_t* header, std::uint32_t length);

/// Incremental frame decoder for one byte stream. Not thread-safe; one per connection.
/// Memory is bounded by max_payload_bytes + kFrameHeaderBytes + the largest piece fed.
class FrameDecoder {
public:
    enum class Status : std::uint8_t {
        frame,     ///< a complete payload was returned
        need_more, ///< no complete frame buffered yet
        too_large, ///< the next frame announces more than max_payload_bytes; the stream is
                   ///< unusable from here (no resynchronisation is possible)
    };

    explicit FrameDecoder(std::uint32_t max_payload_bytes = kDefaultMaxFrameBytes);

    /// Appends received bytes.
    void feed(std::span<const std::uint8_t> bytes);

    /// Takes the next complete frame. On `frame`, `payload` views the payload; it stays
    /// valid until the next call to feed() or next(). After `too_large` every later call
    /// returns `too_large` again.
    [[nodiscard]] Status next(std::span<const std::uint8_t>& payload);

    /// The length announced by the frame that caused `too_large` (0 before that).
    [[nodiscard]] std::uint32_t rejected_length() const { return rejected_length_; }
    [[nodiscard]] std::size_t buffered_bytes() const { return buffer_.size() - read_offset_; }
    [[nodiscard]] std::uint32_t max_payload_bytes() const { return max_payload_bytes_; }

private:
    std::vector<std::uint8_t> buffer_;
    std::size_t read_offset_ = 0;
    std::uint32_t max_payload_bytes_;
    std::uint32_t rejected_length_ = 0;
};

} // namespace dsoc::protocol
