#pragma once
// The .dsocbake.partial file: a bake stopped part way (visibility::BakeState), kept
// beside the table it will become, so that a long bake goes on after a restart instead
// of starting over. The layout is specified in docs/baked-visibility.md ("A bake that
// stops and goes on"). Checked like the table's file before anything in it is used: a
// problem comes back as a LoadError naming the file and what is wrong, and the bake
// then starts from the beginning.

#include "dsoc/maps/load_error.hpp"
#include "dsoc/visibility/cell_bake.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::maps {

/// Bumped on any change of the partial file's layout.
inline constexpr std::uint32_t kBakePartialVersion = 1;

/// A saved bake state with its own rows.
struct PartialBake {
    std::uint64_t key = 0; ///< the key of the table it will become (bake_key())
    std::uint64_t pairs_done = 0;
    std::uint64_t pairs_total = 0;
    std::vector<std::uint64_t> rows;
    visibility::CellBakeStats stats;

    /// The state to resume from (its rows point into this object).
    [[nodiscard]] visibility::BakeState state() const {
        return {pairs_done, pairs_total, rows, stats};
    }
};

/// The partial file's name beside the table's file `table_file`.
[[nodiscard]] std::filesystem::path partial_file_of(const std::filesystem::path& table_file);

/// The file's bytes for `state` of the bake filed under `key`.
[[nodiscard]] std::vector<std::byte> encode_partial(const visibility::BakeState& state,
                                                    std::uint64_t key);

/// Parses and checks `bytes` (read from `name`, for messages); a file of another key
/// than `expected_key` is refused.
[[nodiscard]] Result<PartialBake> decode_partial(std::span<const std::byte> bytes,
                                                 const std::string& name,
                                                 std::uint64_t expected_key);

/// Reads and decodes `path`.
[[nodiscard]] Result<PartialBake> read_partial_file(const std::filesystem::path& path,
                                                    std::uint64_t expected_key);

/// Writes atomically; an error message, or nothing.
[[nodiscard]] std::optional<std::string> write_partial_file(const std::filesystem::path& path,
                                                            const visibility::BakeState& state,
                                                            std::uint64_t key);

} // namespace dsoc::maps
