#include "dsoc/maps/bake_file.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>

#include <unistd.h>

namespace dsoc::maps {

namespace {

constexpr char kMagic[8] = {'D', 'S', 'O', 'C', 'B', 'A', 'K', 'E'};
constexpr std::size_t kHeaderBytes = 80;
constexpr std::size_t kChecksumOffset = 64;
constexpr std::uint64_t kMaxGridCells = kMaxBakeGridCells;
constexpr std::uint64_t kCellsPerOpenCell = kMaxBakeCellsPerOpenCell;

static_assert(std::endian::native == std::endian::little,
              "the .dsocbake layout is little-endian; add byte swaps for this target");

template <class T>
void put(std::vector<std::byte>& out, std::size_t at, T v) {
    std::memcpy(out.data() + at, &v, sizeof v);
}
template <class T>
T get(std::span<const std::byte> in, std::size_t at) {
    T v;
    std::memcpy(&v, in.data() + at, sizeof v);
    return v;
}

std::uint64_t checksum_of_file(std::span<const std::byte> bytes) {
    const std::uint64_t head = bake_checksum(bytes.first(kChecksumOffset));
    return bake_checksum(bytes.subspan(kChecksumOffset + 8), head); // all but itself
}

std::size_t open_list_bytes(std::uint64_t open) {
    return (open * 4 + 7) / 8 * 8;
}

/// The uncovered cells' bitmap: one bit per grid cell, in 64-bit words.
std::size_t uncovered_words(std::uint64_t cells) {
    return static_cast<std::size_t>((cells + 63) / 64);
}

struct Hasher {
    std::uint64_t h = 0xcbf29ce484222325ull;
    void word(std::uint64_t w) { h = bake_checksum(std::as_bytes(std::span(&w, 1)), h); }
    void f32(float v) { word(std::bit_cast<std::uint32_t>(v)); }
    void i64(std::int64_t v) { word(static_cast<std::uint64_t>(v)); }
};

} // namespace

namespace {
/// splitmix64's finaliser: a bijection in which every input bit changes about half of
/// the output bits.
std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
} // namespace

std::uint64_t bake_checksum(std::span<const std::byte> bytes, std::uint64_t seed) {
    std::uint64_t h = seed;
    std::size_t i = 0;
    for (; i + 8 <= bytes.size(); i += 8) {
        std::uint64_t w;
        std::memcpy(&w, bytes.data() + i, 8);
        h = mix(h ^ w) + 0x9e3779b97f4a7c15ull;
    }
    if (i < bytes.size()) {
        std::uint64_t w = 0;
        std::memcpy(&w, bytes.data() + i, bytes.size() - i);
        h = mix(h ^ w) + 0x9e3779b97f4a7c15ull;
    }
    return h;
}

std::uint64_t bake_key_of_map(const Map& map) {
    Hasher k;
    k.word(kBakeFormatVersion);
    k.word(kBakeAlgorithmVersion);
    k.word(map.occluders.size());
    for (const auto& occluder : map.occluders) {
        k.word(occluder.planes().size());
        for (const visibility::Plane& p : occluder.planes()) {
            k.f32(p.normal.x);
            k.f32(p.normal.y);
            k.f32(p.normal.z);
            k.f32(p.distance);
        }
    }
    const int clusters =
        map.pvs != nullptr && map.pvs->has_visibility() ? map.pvs->cluster_count() : 0;
    k.i64(clusters);
    for (int a = 0; a < clusters; ++a) {
        std::uint64_t bits = 0;
        for (int b = 0; b < clusters; ++b) {
            bits = bits << 1 | (map.pvs->cluster_visible(a, b) ? 1u : 0u);
            if ((b & 63) == 63) {
                k.word(bits);
                bits = 0;
            }
        }
        k.word(bits);
    }
    return k.h;
}

std::uint64_t bake_key(std::uint64_t key_of_map, const visibility::CellGrid& grid,
                       const visibility::CellBakeConfig& config,
                       const std::optional<PlayerSpace>& space) {
    Hasher k;
    k.h = key_of_map;
    k.f32(grid.origin.x);
    k.f32(grid.origin.y);
    k.f32(grid.origin.z);
    k.f32(grid.cell_size);
    k.i64(grid.dims.x);
    k.i64(grid.dims.y);
    k.i64(grid.dims.z);
    k.f32(config.cell_size);
    k.i64(config.portal_depth);
    k.i64(config.top_level);
    k.i64(config.witness_stop_level);
    k.i64(config.witness_segments);
    k.i64(config.both_directions ? 1 : 0);
    k.i64(space ? 1 : 0);
    if (space) {
        k.f32(space->min_walk_normal_z);
        k.f32(space->height);
        k.f32(space->margin);
    }
    return k.h;
}

std::uint64_t bake_key(const Map& map, const visibility::CellGrid& grid,
                       const visibility::CellBakeConfig& config,
                       const std::optional<PlayerSpace>& space) {
    return bake_key(bake_key_of_map(map), grid, config, space);
}

std::vector<std::byte> encode_bake(const visibility::CellVisibilityTable& table,
                                   std::uint64_t key) {
    const visibility::CellVisibilityTable* rows = &table;
    visibility::CellVisibilityTable compressed;
    if (!table.compressed()) {
        compressed = table;
        compressed.compress();
        rows = &compressed;
    }
    const auto& grid = table.grid();
    const std::size_t open = table.open_count();
    const std::size_t list = open_list_bytes(open);
    std::vector<std::uint64_t> uncovered(uncovered_words(grid.cell_count()), 0);
    for (const std::uint32_t c : table.uncovered_cells()) {
        uncovered[c >> 6] |= std::uint64_t{1} << (c & 63);
    }
    const std::size_t rows_at = kHeaderBytes + list + uncovered.size() * 8;
    const auto classes = rows->classes();
    const auto literals = rows->literals();
    std::vector<std::byte> out(rows_at + (classes.size() + literals.size()) * 8);
    std::memcpy(out.data(), kMagic, 8);
    put<std::uint32_t>(out, 8, kBakeFormatVersion);
    put<std::uint32_t>(out, 12, static_cast<std::uint32_t>(kHeaderBytes));
    put<std::uint64_t>(out, 16, key);
    put<float>(out, 24, grid.cell_size);
    put<float>(out, 28, grid.origin.x);
    put<float>(out, 32, grid.origin.y);
    put<float>(out, 36, grid.origin.z);
    put<std::int32_t>(out, 40, grid.dims.x);
    put<std::int32_t>(out, 44, grid.dims.y);
    put<std::int32_t>(out, 48, grid.dims.z);
    put<std::uint32_t>(out, 52, static_cast<std::uint32_t>(open));
    put<std::uint64_t>(out, 56, table.words_per_row());
    put<std::uint64_t>(out, 72, literals.size());
    // memcpy from an empty span's null data() is undefined: copy only what is there.
    if (open > 0) {
        std::memcpy(out.data() + kHeaderBytes, table.open_cells().data(), open * 4);
    }
    std::memcpy(out.data() + kHeaderBytes + list, uncovered.data(), uncovered.size() * 8);
    if (!classes.empty()) {
        std::memcpy(out.data() + rows_at, classes.data(), classes.size() * 8);
    }
    if (!literals.empty()) {
        std::memcpy(out.data() + rows_at + classes.size() * 8, literals.data(),
                    literals.size() * 8);
    }
    put<std::uint64_t>(out, kChecksumOffset, checksum_of_file(out));
    return out;
}

Result<visibility::CellVisibilityTable> decode_bake(std::span<const std::byte> bytes,
                                                    const std::string& name,
                                                    std::optional<std::uint64_t> expected_key) {
    const auto fail = [&](const std::string& part, const std::string& what) {
        return LoadError{name, part, what};
    };
    if (bytes.size() < kHeaderBytes) {
        return fail("header", "truncated: " + std::to_string(bytes.size()) +
                                  " bytes, the header alone is " + std::to_string(kHeaderBytes));
    }
    if (std::memcmp(bytes.data(), kMagic, 8) != 0) {
        return fail("header", "not a .dsocbake file (bad magic)");
    }
    const auto version = get<std::uint32_t>(bytes, 8);
    if (version != kBakeFormatVersion) {
        return fail("header", "format version " + std::to_string(version) + ", this build reads " +
                                  std::to_string(kBakeFormatVersion));
    }
    if (get<std::uint32_t>(bytes, 12) != kHeaderBytes) {
        return fail("header", "header size " + std::to_string(get<std::uint32_t>(bytes, 12)) +
                                  ", expected " + std::to_string(kHeaderBytes));
    }
    visibility::CellGrid grid;
    grid.cell_size = get<float>(bytes, 24);
    grid.origin = {get<float>(bytes, 28), get<float>(bytes, 32), get<float>(bytes, 36)};
    grid.dims = {get<std::int32_t>(bytes, 40), get<std::int32_t>(bytes, 44),
                 get<std::int32_t>(bytes, 48)};
    if (!(grid.cell_size >= 1.0f && grid.cell_size <= 4096.0f) || !std::isfinite(grid.origin.x) ||
        !std::isfinite(grid.origin.y) || !std::isfinite(grid.origin.z) ||
        std::abs(grid.origin.x) > 1e7f || std::abs(grid.origin.y) > 1e7f ||
        std::abs(grid.origin.z) > 1e7f) {
        return fail("header", "grid origin or cell size out of range");
    }
    // One factor at a time: three sides of up to 2^31 would overflow 64 bits (and wrap
    // to a small count) if multiplied at once.
    const auto dims_fit = [&] {
        std::uint64_t cells = 1;
        for (const std::int32_t side : {grid.dims.x, grid.dims.y, grid.dims.z}) {
            if (side < 1 || static_cast<std::uint64_t>(side) > kMaxGridCells) {
                return false;
            }
            cells *= static_cast<std::uint64_t>(side); // both factors <= 2^24: no overflow
            if (cells > kMaxGridCells) {
                return false;
            }
        }
        return true;
    };
    if (!dims_fit()) {
        return fail("header", "grid dimensions out of range");
    }
    const std::uint64_t open = get<std::uint32_t>(bytes, 52);
    const std::uint64_t words_per_row = get<std::uint64_t>(bytes, 56);
    // Real grids hold at most a few grid cells per open cell (the bake's grid is the
    // map's bounds); a grid far larger than its open cells would only cost memory.
    if (grid.cell_count() > kCellsPerOpenCell * std::max<std::uint64_t>(open, 64)) {
        return fail("header", std::to_string(grid.cell_count()) + " grid cells for " +
                                  std::to_string(open) + " open cells: more than " +
                                  std::to_string(kCellsPerOpenCell) + " per open cell");
    }
    if (open > grid.cell_count()) {
        return fail("header", "more open cells (" + std::to_string(open) + ") than cells (" +
                                  std::to_string(grid.cell_count()) + ")");
    }
    if (words_per_row != (open + 63) / 64) {
        return fail("header", "words per row " + std::to_string(words_per_row) + " do not fit " +
                                  std::to_string(open) + " open cells");
    }
    const std::uint64_t class_words = open * ((words_per_row + 31) / 32);
    const std::uint64_t literal_words = get<std::uint64_t>(bytes, 72);
    if (literal_words > kMaxBakeFileBytes / 8) {
        return fail("header", std::to_string(literal_words) + " literal words: over the limit");
    }
    const std::size_t uncovered_at = kHeaderBytes + open_list_bytes(open);
    const std::size_t rows_at = uncovered_at + uncovered_words(grid.cell_count()) * 8;
    const std::uint64_t expected_size = rows_at + (class_words + literal_words) * 8;
    if (expected_size > kMaxBakeFileBytes) {
        return fail("header", "table of " + std::to_string(expected_size) +
                                  " bytes is over the limit of " +
                                  std::to_string(kMaxBakeFileBytes));
    }
    if (bytes.size() != expected_size) {
        return fail("", (bytes.size() < expected_size ? "truncated: " : "trailing bytes: ") +
                            std::to_string(bytes.size()) + " bytes, the header says " +
                            std::to_string(expected_size));
    }
    if (get<std::uint64_t>(bytes, kChecksumOffset) != checksum_of_file(bytes)) {
        return fail("", "checksum mismatch: the file is corrupt");
    }
    const std::uint64_t key = get<std::uint64_t>(bytes, 16);
    if (expected_key && key != *expected_key) {
        return fail("header", "made for another map or other bake settings (key " +
                                  std::to_string(key) + ", expected " +
                                  std::to_string(*expected_key) + ")");
    }
    std::vector<std::uint32_t> cells(open);
    if (open > 0) {
        std::memcpy(cells.data(), bytes.data() + kHeaderBytes, open * 4);
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
        if (cells[i] >= grid.cell_count()) {
            return fail("open cells", "entry " + std::to_string(i) + " is out of range");
        }
    }
    std::vector<std::uint32_t> uncovered;
    for (std::size_t w = 0; w < uncovered_words(grid.cell_count()); ++w) {
        for (auto bits = get<std::uint64_t>(bytes, uncovered_at + w * 8); bits != 0;
             bits &= bits - 1) {
            const std::uint64_t c = w * 64 + static_cast<std::uint64_t>(std::countr_zero(bits));
            if (c >= grid.cell_count()) {
                return fail("uncovered cells", "a bit past the last grid cell");
            }
            uncovered.push_back(static_cast<std::uint32_t>(c));
        }
    }
    visibility::CellVisibilityTable table(grid, cells, uncovered,
                                          visibility::CellVisibilityTable::Rows::none);
    for (std::size_t i = 0; i < cells.size(); ++i) {
        if (table.open_cells()[i] != cells[i] ||
            (i > 0 && table.block_rank(cells[i]) <= table.block_rank(cells[i - 1]))) {
            return fail("open cells",
                        "entry " + std::to_string(i) + " is repeated or not in block order");
        }
    }
    for (const std::uint32_t c : uncovered) {
        if (table.open_index(c) != visibility::kUncoveredCell) {
            return fail("uncovered cells",
                        "grid cell " + std::to_string(c) + " is both open and uncovered");
        }
    }
    std::vector<std::uint64_t> classes(class_words);
    std::vector<std::uint64_t> literals(literal_words);
    if (!classes.empty()) {
        std::memcpy(classes.data(), bytes.data() + rows_at, class_words * 8);
    }
    if (!literals.empty()) {
        std::memcpy(literals.data(), bytes.data() + rows_at + class_words * 8, literal_words * 8);
    }
    if (auto problem = table.adopt_compressed(std::move(classes), std::move(literals))) {
        return fail("rows", *problem);
    }
    return table;
}

Result<std::vector<std::byte>> read_cache_file(const std::filesystem::path& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) {
        return LoadError{path.string(), "", "cannot read: " + ec.message()};
    }
    if (size > kMaxBakeFileBytes) {
        return LoadError{path.string(), "",
                         "file of " + std::to_string(size) + " bytes is over the limit of " +
                             std::to_string(kMaxBakeFileBytes)};
    }
    std::vector<std::byte> bytes(static_cast<std::size_t>(size));
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
        return LoadError{path.string(), "", "cannot read the file"};
    }
    return bytes;
}

std::optional<std::string> write_cache_file(const std::filesystem::path& path,
                                            std::span<const std::byte> bytes) {
    return write_cache_file(path, {bytes});
}

std::optional<std::string>
write_cache_file(const std::filesystem::path& path,
                 std::initializer_list<std::span<const std::byte>> parts) {
    std::error_code ec;
    if (path.has_parent_path()) {
        std::filesystem::create_directories(path.parent_path(), ec);
        if (ec) {
            return "cannot create " + path.parent_path().string() + ": " + ec.message();
        }
    }
    // A name of its own, so that two bakers at once never write into one file.
    static std::atomic<unsigned> counter{0};
    auto temp = path;
    std::string suffix = std::to_string(::getpid());
    suffix += '.';
    suffix += std::to_string(counter++);
    suffix += ".tmp";
    temp += '.';
    temp += suffix;
    {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        for (const auto& bytes : parts) {
            out.write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
        }
        out.close();
        if (!out) {
            std::filesystem::remove(temp, ec);
            return "cannot write " + temp.string();
        }
    }
    std::filesystem::rename(temp, path, ec);
    if (ec) {
        return "cannot rename " + temp.string() + " to " + path.string() + ": " + ec.message();
    }
    return std::nullopt;
}

Result<visibility::CellVisibilityTable> read_bake_file(const std::filesystem::path& path,
                                                       std::optional<std::uint64_t> expected_key) {
    auto bytes = read_cache_file(path);
    if (!bytes) {
        return bytes.error();
    }
    return decode_bake(bytes.value(), path.string(), expected_key);
}

std::optional<std::string> write_bake_file(const std::filesystem::path& path,
                                           const visibility::CellVisibilityTable& table,
                                           std::uint64_t key) {
    return write_cache_file(path, encode_bake(table, key));
}

} // namespace dsoc::maps
