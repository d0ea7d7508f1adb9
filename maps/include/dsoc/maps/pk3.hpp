#pragma once
// Reading entries out of .pk3 archives (zip files) with libzip.

#include "dsoc/maps/load_error.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::maps {

/// Largest entry read_pk3_entry() accepts. [Units: bytes]
inline constexpr std::size_t kMaxPk3EntryBytes = 256u * 1024u * 1024u;

/// Reads one entry (e.g. "maps/oa_dm4.bsp", matched case-insensitively, as Quake 3
/// does), always to its end, so that damage never passes as data: the bytes are
/// returned only if they decompress cleanly, number exactly the size the archive's
/// directory declares and match its CRC-32. Errors (a LoadError whose file is the
/// archive, lump the entry and what the failure): archive missing, truncated or
/// inconsistent; entry missing or larger than kMaxPk3EntryBytes; compressed data
/// invalid; CRC-32 mismatch; size mismatch (fewer or more bytes than declared).
[[nodiscard]] Result<std::vector<std::byte>> read_pk3_entry(const std::filesystem::path& pk3,
                                                            std::string_view entry);

/// The entries directly in `folder` (e.g. "scripts/") whose names end in `extension`
/// (e.g. ".shader"), both matched case-insensitively: each as its name between the two,
/// in the archive's case, sorted.
[[nodiscard]] Result<std::vector<std::string>> list_pk3_entries_in(const std::filesystem::path& pk3,
                                                                   std::string_view folder,
                                                                   std::string_view extension);
/// One entry of read_pk3_entries_in(): its full name in the archive and its bytes, or
/// why they did not read (as read_pk3_entry() says it).
struct Pk3EntryRead {
    std::string name;
    Result<std::vector<std::byte>> bytes;
};
/// Every entry list_pk3_entries_in() lists, each read as read_pk3_entry() reads one, the
/// archive opened once. An error only when the archive does not open; an entry that does
/// not read carries its own error.
[[nodiscard]] Result<std::vector<Pk3EntryRead>>
read_pk3_entries_in(const std::filesystem::path& pk3, std::string_view folder,
                    std::string_view extension);
/// Names of the maps in an archive: "maps/<name>.bsp" entries give "<name>", sorted.
[[nodiscard]] Result<std::vector<std::string>> list_pk3_maps(const std::filesystem::path& pk3);

} // namespace dsoc::maps
