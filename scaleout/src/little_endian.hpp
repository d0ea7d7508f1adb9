#pragma once
// The scale-out messages' byte order (docs/scale-out.md): little-endian, written and
// read as the host's own, which this build checks is little-endian.

#include <bit>
#include <cstddef>
#include <cstring>
#include <span>
#include <type_traits>
#include <vector>

namespace dsoc::scaleout {

static_assert(std::endian::native == std::endian::little,
              "the scale-out messages are little-endian; add byte swaps for this target");

/// Appends `value`'s bytes to `out`.
template <typename T>
void put(std::vector<std::byte>& out, T value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t at = out.size();
    out.resize(at + sizeof(T));
    std::memcpy(out.data() + at, &value, sizeof(T));
}

/// The T at byte `at` of `bytes`. Precondition: at + sizeof(T) <= bytes.size().
template <typename T>
[[nodiscard]] T get(std::span<const std::byte> bytes, std::size_t at) {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    std::memcpy(&value, bytes.data() + at, sizeof(T));
    return value;
}

} // namespace dsoc::scaleout
