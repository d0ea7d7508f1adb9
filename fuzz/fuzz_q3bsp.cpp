// Fuzzes the Quake 3 BSP parser and the BSP -> Map rules (geometry included): any
// bytes must give a Map or a LoadError, never a crash, a sanitizer report or a hang.

#include "dsoc/maps/q3_bsp.hpp"
#include "dsoc/maps/q3_map.hpp"

#include <cstddef>
#include <cstdint>
#include <span>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
    auto bsp = dsoc::maps::q3::parse_q3_bsp(bytes, "fuzz.bsp");
    if (!bsp.ok()) {
        (void)bsp.error().message();
        return 0;
    }
    auto map = dsoc::maps::map_from_q3_bsp(bsp.value(), "fuzz");
    if (!map.ok()) {
        (void)map.error().message();
    }
    return 0;
}
