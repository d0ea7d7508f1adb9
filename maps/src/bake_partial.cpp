#include "dsoc/maps/bake_partial.hpp"

#include "dsoc/maps/bake_file.hpp"

#include <bit>
#include <cmath>
#include <cstring>

namespace dsoc::maps {

namespace {

constexpr char kMagic[8] = {'D', 'S', 'O', 'C', 'P', 'A', 'R', 'T'};
constexpr std::size_t kChecksumOffset = 48;
constexpr std::size_t kStatsOffset = 56;
/// The counts: six totals, exact tests and proofs by level (7 each), seconds.
constexpr std::size_t kStatsWords = 6 + 7 + 7 + 1;
constexpr std::size_t kHeaderBytes = kStatsOffset + 8 * kStatsWords;

static_assert(std::endian::native == std::endian::little,
              "the partial file is little-endian; add byte swaps for this target");

void put(std::vector<std::byte>& out, std::size_t at, std::uint64_t v) {
    std::memcpy(out.data() + at, &v, sizeof v);
}
std::uint64_t get(std::span<const std::byte> in, std::size_t at) {
    std::uint64_t v;
    std::memcpy(&v, in.data() + at, sizeof v);
    return v;
}

std::uint64_t checksum_of(std::span<const std::byte> bytes) {
    const std::uint64_t head = bake_checksum(bytes.first(kChecksumOffset));
    return bake_checksum(bytes.subspan(kChecksumOffset + 8), head); // all but itself
}

std::vector<std::uint64_t*> stat_words(visibility::CellBakeStats& s) {
    std::vector<std::uint64_t*> w{&s.pair_visits,   &s.pruned,      &s.witness_rays,
                                  &s.witness_clear, &s.exact_tests, &s.exact_hidden};
    for (auto& v : s.exact_by_level) {
        w.push_back(&v);
    }
    for (auto& v : s.hidden_by_level) {
        w.push_back(&v);
    }
    return w;
}

} // namespace

std::filesystem::path partial_file_of(const std::filesystem::path& table_file) {
    auto p = table_file;
    p += ".partial";
    return p;
}

namespace {

/// The header, its checksum taken over it and the rows that follow it in the file (so
/// that a save writes the rows where they are, without a copy).
std::vector<std::byte> header_of(const visibility::BakeState& state, std::uint64_t key) {
    std::vector<std::byte> out(kHeaderBytes);
    std::memcpy(out.data(), kMagic, sizeof kMagic);
    const std::uint32_t version = kBakePartialVersion;
    const auto header = static_cast<std::uint32_t>(kHeaderBytes);
    std::memcpy(out.data() + 8, &version, 4);
    std::memcpy(out.data() + 12, &header, 4);
    put(out, 16, key);
    put(out, 24, state.pairs_total);
    put(out, 32, state.pairs_done);
    put(out, 40, state.rows.size());
    visibility::CellBakeStats stats = state.stats;
    std::size_t at = kStatsOffset;
    for (const std::uint64_t* w : stat_words(stats)) {
        put(out, at, *w);
        at += 8;
    }
    put(out, at, std::bit_cast<std::uint64_t>(stats.seconds));
    const std::span<const std::byte> head(out);
    std::uint64_t h = bake_checksum(head.first(kChecksumOffset));
    h = bake_checksum(head.subspan(kChecksumOffset + 8), h);
    // The header is a whole number of words, so the rows continue the same sum.
    static_assert(kHeaderBytes % 8 == 0);
    h = bake_checksum(std::as_bytes(state.rows), h);
    put(out, kChecksumOffset, h);
    return out;
}

} // namespace

std::vector<std::byte> encode_partial(const visibility::BakeState& state, std::uint64_t key) {
    std::vector<std::byte> out = header_of(state, key);
    const auto rows = std::as_bytes(state.rows);
    out.insert(out.end(), rows.begin(), rows.end());
    return out;
}

Result<PartialBake> decode_partial(std::span<const std::byte> bytes, const std::string& name,
                                   std::uint64_t expected_key) {
    const auto fail = [&](std::string what) { return LoadError{name, "", std::move(what)}; };
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) {
        return fail("not a partial bake file (no DSOCPART header)");
    }
    std::uint32_t version;
    std::uint32_t header;
    std::memcpy(&version, bytes.data() + 8, 4);
    std::memcpy(&header, bytes.data() + 12, 4);
    if (version != kBakePartialVersion) {
        return fail("partial bake format version " + std::to_string(version) + ", expected " +
                    std::to_string(kBakePartialVersion));
    }
    if (header != kHeaderBytes) {
        return fail("header size " + std::to_string(header) + ", expected " +
                    std::to_string(kHeaderBytes));
    }
    PartialBake p;
    p.key = get(bytes, 16);
    p.pairs_total = get(bytes, 24);
    p.pairs_done = get(bytes, 32);
    const std::uint64_t words = get(bytes, 40);
    if ((bytes.size() - kHeaderBytes) % 8 != 0 || words != (bytes.size() - kHeaderBytes) / 8) {
        return fail("file of " + std::to_string(bytes.size()) + " bytes does not hold the " +
                    std::to_string(words) + " row words its header names (truncated?)");
    }
    if (get(bytes, kChecksumOffset) != checksum_of(bytes)) {
        return fail("checksum mismatch (the file is corrupt)");
    }
    if (p.key != expected_key) {
        return fail("made for another map or other settings (key differs)");
    }
    if (p.pairs_done > p.pairs_total) {
        return fail(std::to_string(p.pairs_done) + " pairs done of " +
                    std::to_string(p.pairs_total));
    }
    std::size_t at = kStatsOffset;
    for (std::uint64_t* w : stat_words(p.stats)) {
        *w = get(bytes, at);
        at += 8;
    }
    p.stats.seconds = std::bit_cast<double>(get(bytes, at));
    if (!std::isfinite(p.stats.seconds) || p.stats.seconds < 0.0) {
        return fail("the bake's time so far is not a number of seconds");
    }
    p.rows.resize(static_cast<std::size_t>(words));
    if (words > 0) {
        std::memcpy(p.rows.data(), bytes.data() + kHeaderBytes, 8 * p.rows.size());
    }
    return p;
}

Result<PartialBake> read_partial_file(const std::filesystem::path& path,
                                      std::uint64_t expected_key) {
    auto bytes = read_cache_file(path);
    if (!bytes) {
        return bytes.error();
    }
    return decode_partial(bytes.value(), path.string(), expected_key);
}

std::optional<std::string> write_partial_file(const std::filesystem::path& path,
                                              const visibility::BakeState& state,
                                              std::uint64_t key) {
    const std::vector<std::byte> header = header_of(state, key);
    return write_cache_file(path, {std::span<const std::byte>(header), std::as_bytes(state.rows)});
}

} // namespace dsoc::maps
