#pragma once
// The .dsocbake file: a CellVisibilityTable on disk, versioned, checksummed and keyed
// by what it was baked from (the map's occluders and PVS, the grid, the bake
// settings). The layout is specified in docs/baked-visibility.md ("The file").
// Nothing read from such a file is trusted: every field and the checksum are checked,
// and any problem comes back as a LoadError naming the file and what is wrong.

#include "dsoc/maps/load_error.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/maps/player_space.hpp"
#include "dsoc/visibility/cell_bake.hpp"
#include "dsoc/visibility/cell_visibility.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::maps {

/// Bumped on any change of the layout or of what the bits mean.
inline constexpr std::uint32_t kBakeFormatVersion = 4;
/// Part of every key: bumped on any change to what the bake may prove (the bake, the
/// exact region tests it runs, the open-cell rules, the PVS pruner), so that tables
/// baked by older code are baked again, never trusted.
inline constexpr std::uint32_t kBakeAlgorithmVersion = 2;
/// Grids larger than this many cells are refused (2^24: 16.7M cells, 128 MiB of
/// per-cell indexes when loaded). [Units: cells]
inline constexpr std::uint64_t kMaxBakeGridCells = std::uint64_t{1} << 24;
/// Grid cells allowed per open cell (counting at least 64 open cells): a small file
/// cannot make the reader allocate much.
inline constexpr std::uint64_t kMaxBakeCellsPerOpenCell = 1024;
/// Largest file read or written. [Units: bytes]
inline constexpr std::uint64_t kMaxBakeFileBytes = std::uint64_t{1} << 30;

/// The key a table is filed under: a 64-bit hash of the format and algorithm versions,
/// the map's occluders (every solid plane), its PVS (cluster count and every cluster
/// pair's bit), the grid, the settings that change the result (not `threads`) and the
/// player space the table covers (nothing: the whole box).
[[nodiscard]] std::uint64_t bake_key(const Map& map, const visibility::CellGrid& grid,
                                     const visibility::CellBakeConfig& config,
                                     const std::optional<PlayerSpace>& space);
/// bake_key() in two steps, for the keys of several grids of one map: the hash state
/// after the versions and the map (its occluders and PVS), then the grid and settings
/// hashed on from it. bake_key(bake_key_of_map(map), grid, config) is bake_key(map,
/// grid, config).
[[nodiscard]] std::uint64_t bake_key_of_map(const Map& map);
[[nodiscard]] std::uint64_t bake_key(std::uint64_t key_of_map, const visibility::CellGrid& grid,
                                     const visibility::CellBakeConfig& config,
                                     const std::optional<PlayerSpace>& space);

/// The file's checksum function over `bytes` (see the spec): 64-bit words, each mixed
/// into the state with splitmix64's finaliser.
[[nodiscard]] std::uint64_t bake_checksum(std::span<const std::byte> bytes,
                                          std::uint64_t seed = 0xcbf29ce484222325ull);

/// The file's bytes for `table` under `key`.
[[nodiscard]] std::vector<std::byte> encode_bake(const visibility::CellVisibilityTable& table,
                                                 std::uint64_t key);

/// Parses and checks `bytes` (read from `name`, for messages). With `expected_key`,
/// a file of another key is refused ("made for another map or other settings").
[[nodiscard]] Result<visibility::CellVisibilityTable>
decode_bake(std::span<const std::byte> bytes, const std::string& name,
            std::optional<std::uint64_t> expected_key = std::nullopt);

/// The whole of `path`, at most kMaxBakeFileBytes (a cache file of any kind).
[[nodiscard]] Result<std::vector<std::byte>> read_cache_file(const std::filesystem::path& path);

/// Writes `bytes` to `path` atomically (a temporary file beside it, then a rename), so
/// that a reader never sees half a file. Returns an error message, or nothing.
[[nodiscard]] std::optional<std::string> write_cache_file(const std::filesystem::path& path,
                                                          std::span<const std::byte> bytes);
/// The same for a file of several parts written one after another (no copy of them).
[[nodiscard]] std::optional<std::string>
write_cache_file(const std::filesystem::path& path,
                 std::initializer_list<std::span<const std::byte>> parts);

/// Reads and decodes `path`.
[[nodiscard]] Result<visibility::CellVisibilityTable>
read_bake_file(const std::filesystem::path& path,
               std::optional<std::uint64_t> expected_key = std::nullopt);

/// Writes atomically (a temporary file beside `path`, then a rename). Returns an
/// error message, or nothing.
[[nodiscard]] std::optional<std::string>
write_bake_file(const std::filesystem::path& path, const visibility::CellVisibilityTable& table,
                std::uint64_t key);

} // namespace dsoc::maps
