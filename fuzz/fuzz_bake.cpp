// Fuzzes the .dsocbake reader (dsoc/maps/bake_file.hpp) and the partial bake's
// (dsoc/maps/bake_partial.hpp): the bytes as they are, then with their checksum made
// right so that mutations reach the checks behind it. What a reader accepts must
// survive encode -> decode unchanged, and its rows read whole, bit by bit and united
// over blocks of cells must agree.

#include "dsoc/maps/bake_file.hpp"
#include "dsoc/maps/bake_partial.hpp"
#include "dsoc/visibility/cell_block_unions.hpp"
#include "dsoc/visibility/cell_visibility.hpp"

#include <glm/common.hpp>
#include <glm/vector_relational.hpp>

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
// The partial file's (docs/baked-visibility.md, "A bake that stops and goes on").
constexpr std::size_t kPartialChecksumOffset = 48;
constexpr std::size_t kPartialHeaderBytes = 224;

void fuzz_partial(std::vector<std::byte> bytes) {
    (void)dsoc::maps::decode_partial(bytes, "fuzz.partial", 0);
    if (bytes.size() < kPartialHeaderBytes) {
        return;
    }
    const std::span<const std::byte> all(bytes);
    const std::uint64_t checksum =
        dsoc::maps::bake_checksum(all.subspan(kPartialChecksumOffset + 8),
                                  dsoc::maps::bake_checksum(all.first(kPartialChecksumOffset)));
    std::memcpy(bytes.data() + kPartialChecksumOffset, &checksum, sizeof checksum);
    std::uint64_t key = 0;
    std::memcpy(&key, bytes.data() + kKeyOffset, sizeof key);
    const auto partial = dsoc::maps::decode_partial(bytes, "fuzz.partial", key);
    if (!partial.ok()) {
        (void)partial.error().message();
        return;
    }
    const auto again = dsoc::maps::decode_partial(
        dsoc::maps::encode_partial(partial.value().state(), key), "again", key);
    if (!again.ok() || again.value().rows != partial.value().rows ||
        again.value().pairs_done != partial.value().pairs_done ||
        again.value().pairs_total != partial.value().pairs_total ||
        again.value().stats.exact_tests != partial.value().stats.exact_tests) {
        std::abort(); // encode_partial wrote something decode_partial reads differently
    }
}

/// The rows of an accepted table as the runtime reads them, a whole row at a time
/// (or_row_into) and a bit at a time (may_see): the two must agree (the first rows only,
/// to bound the work of a large table).
void check_rows(const dsoc::visibility::CellVisibilityTable& table) {
    constexpr std::size_t kMaxRows = 64;
    const std::size_t cells = table.open_count();
    std::vector<std::uint64_t> row(table.words_per_row());
    for (std::size_t a = 0; a < std::min(cells, kMaxRows); ++a) {
        std::ranges::fill(row, std::uint64_t{0});
        table.or_row_into(static_cast<dsoc::visibility::OpenCell>(a), row);
        for (std::size_t b = 0; b < cells; ++b) {
            const bool bit = (row[b / 64] >> (b % 64) & 1u) != 0;
            if (bit != table.may_see(static_cast<dsoc::visibility::OpenCell>(a),
                                     static_cast<dsoc::visibility::OpenCell>(b))) {
                std::abort(); // the two readers of a row disagree
            }
        }
        if (cells % 64 != 0 && !row.empty() && (row.back() >> (cells % 64)) != 0) {
            std::abort(); // a bit past the last open cell
        }
    }
}

/// The block unions of an accepted table (small grids only, to bound the work) against
/// the rows they unite, over the ranges of up to 4 cells an axis at the grid's corner.
void check_block_unions(const dsoc::visibility::CellVisibilityTable& table) {
    using dsoc::visibility::CellBlockUnions;
    const dsoc::visibility::CellGrid& grid = table.grid();
    if (grid.cell_count() > (1u << 16)) {
        return;
    }
    const CellBlockUnions blocks(table);
    std::vector<std::uint64_t> rows(table.words_per_row());
    std::vector<std::uint64_t> united(table.words_per_row());
    for (int n = 2; n <= 4; ++n) {
        const glm::ivec3 lo{0}; // the grid's corner
        const glm::ivec3 hi = glm::min(grid.dims, glm::ivec3(n)) - 1;
        if (!CellBlockUnions::covers(lo, hi)) {
            return;
        }
        std::ranges::fill(rows, std::uint64_t{0});
        for (std::uint32_t cell = 0; cell < grid.cell_count(); ++cell) { // every cell in range
            const auto c = table.open_index(cell);
            if (c >= 0 && glm::all(glm::lessThanEqual(grid.coords(cell), hi))) {
                table.or_row_into(c, rows);
            }
        }
        std::ranges::fill(united, std::uint64_t{0});
        blocks.or_range_into(lo, hi, united);
        if (united != rows) {
            std::abort(); // a range's union from blocks is not the union of its rows
        }
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<std::byte> bytes(reinterpret_cast<const std::byte*>(data),
                                 reinterpret_cast<const std::byte*>(data) + size);
    fuzz_partial(bytes);
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
    check_rows(table.value());
    check_block_unions(table.value());
    return 0;
}
