#pragma once
// How the snapshot fuzz targets read their input: the first byte picks the angle
// steps, and the rest is messages, each a length byte and then that many bytes (fewer
// at the end of the input).

#include "dsoc/protocol/quantization.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace dsoc::fuzzing {

/// The default settings with 256 + 255 * `first` (256 .. 65281) angle steps.
inline protocol::QuantizationSettings settings_from(std::uint8_t first) {
    protocol::QuantizationSettings settings;
    settings.angle_steps = 256u + 255u * first;
    return settings;
}

/// Calls f(bytes, count) for every length-prefixed piece of data[at, size).
template <class F>
void for_each_length_prefixed(const std::uint8_t* data, std::size_t size, std::size_t at, F&& f) {
    while (at < size) {
        const std::size_t n = std::min<std::size_t>(data[at], size - at - 1);
        ++at;
        f(data + at, n);
        at += n;
    }
}

} // namespace dsoc::fuzzing
