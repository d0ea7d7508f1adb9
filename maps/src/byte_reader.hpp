#pragma once
// Little-endian decoding of records whose bounds the caller has already checked.
// Private to dsoc::maps.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace dsoc::maps::detail {

/// Precondition: offset + 4 <= bytes.size() (asserted by the callers' range checks).
inline std::uint32_t read_u32(std::span<const std::byte> bytes, std::size_t offset) {
    return static_cast<std::uint32_t>(bytes[offset]) |
           (static_cast<std::uint32_t>(bytes[offset + 1]) << 8) |
           (static_cast<std::uint32_t>(bytes[offset + 2]) << 16) |
           (static_cast<std::uint32_t>(bytes[offset + 3]) << 24);
}

inline std::int32_t read_i32(std::span<const std::byte> bytes, std::size_t offset) {
    return std::bit_cast<std::int32_t>(read_u32(bytes, offset));
}

inline float read_f32(std::span<const std::byte> bytes, std::size_t offset) {
    return std::bit_cast<float>(read_u32(bytes, offset));
}

} // namespace dsoc::maps::detail
