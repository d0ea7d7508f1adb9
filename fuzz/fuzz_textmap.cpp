// Fuzzes our text map format: parse, build the geometry, and check that a parsed
// map survives format -> parse.

#include "dsoc/maps/map_spec.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    auto spec = dsoc::maps::parse_text_map(text, "fuzz.dsocmap");
    if (!spec.ok()) {
        (void)spec.error().message();
        return 0;
    }
    (void)dsoc::maps::build_map(spec.value(), "fuzz");
    auto again = dsoc::maps::parse_text_map(dsoc::maps::format_text_map(spec.value()), "again");
    if (!again.ok() || again.value().brushes.size() != spec.value().brushes.size() ||
        again.value().spawn_points.size() != spec.value().spawn_points.size()) {
        std::abort(); // format_text_map wrote something parse_text_map rejects
    }
    return 0;
}
