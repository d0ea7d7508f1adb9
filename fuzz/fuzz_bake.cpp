// Fuzzes the .dsocbake reader (dsoc/maps/bake_file.hpp): the bytes as they are, then
// with their checksum made right so that mutations reach the checks behind it. A
// table the reader accepts must survive encode -> decode unchanged.

#include "dsoc/maps/bake_file.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

namespace {

// Layout of the header (docs/baked-visibility.md, "The file").
constexpr std::size_t kKeyOffset = 16;
constexpr std::size_t kChecksumOffset = 64;
constexpr std::size_t kHeaderBytes = 80;

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<std::byte> bytes(reinterpret_cast<const std::byte*>(data),
                                 reinterpret_cast<const std::byte*>(data) + size);
    (void)dsoc::maps::decode_bake(bytes, "fuzz.dsocbake");
    if (bytes.size() < kHeaderBytes) {
        return 0;
    }
    const std::span<const std::byte> all(bytes);
    const std::uint64_t checksum = dsoc::maps::bake_checksum(
        all.subspan(kChecksumOffset + 8), dsoc::maps::bake_checksum(all.first(kChecksumOffset)));
    std::memcpy(bytes.data() + kChecksumOffset, &checksum, sizeof checksum);
    auto table = dsoc::maps::decode_bake(bytes, "fuzz.dsocbake");
    if (!table.ok()) {
        (void)table.error().message();
        return 0;
    }
    std::uint64_t key = 0;
    std::memcpy(&key, bytes.data() + kKeyOffset, sizeof key);
    const auto again =
        dsoc::maps::decode_bake(dsoc::maps::encode_bake(table.value(), key), "again", key);
    if (!again.ok() || !(again.value() == table.value())) {
        std::abort(); // encode_bake wrote something decode_bake reads differently
    }
    return 0;
}
