#pragma once
// The answer of every conservative visibility test in dsoc::visibility.

#include <cstdint>

namespace dsoc::visibility {

/// Answer of a conservative occlusion query.
///  - `visible`: the query could not prove occlusion. It MAY be a false positive
///    (the item is in fact hidden); callers must treat it as "possibly visible".
///  - `occluded`: proven hidden: every segment from the eye to every point of the
///    item passes through the interior of some occluder. Never a false positive,
///    up to the floating-point margins each test documents (which err towards
///    `visible`).
enum class Visibility : std::uint8_t { visible, occluded };

[[nodiscard]] constexpr const char* to_string(Visibility v) noexcept {
    return v == Visibility::visible ? "visible" : "occluded";
}

} // namespace dsoc::visibility
