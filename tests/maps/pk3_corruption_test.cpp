// Damaged .pk3 archives never load: a corpus generated here (bit flips in the
// compressed data, a wrong CRC-32, wrong declared sizes, a truncated entry, truncated
// archives, headers that disagree), each refused with a LoadError naming the archive,
// the entry and what failed, while the intact archive loads. Also the audit's case:
// bit flips in real OpenArena maps copied, still compressed, into archives of their own.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/pk3.hpp"
#include "test_support.hpp"
#include "zip_corpus.hpp"

#include <gtest/gtest.h>
#include <zip.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <unistd.h>

namespace dsoc::maps {
namespace {

namespace fs = std::filesystem;
using test::ZipEntry;
using test::ZipLayout;

constexpr const char* kEntry = "maps/tiny.bsp";

/// Tallies of one corruption kind, printed for the record (the closing note).
struct Tally {
    std::size_t archives = 0;
    std::size_t loaded = 0;
    std::map<std::string, std::size_t>
        by_reason; ///< refusals by the first words of the reason, and identical loads
};

std::string reason_kind(const std::string& what) {
    for (const char* kind :
         {"CRC-32 mismatch", "size mismatch", "compressed data is invalid", "cannot open archive",
          "inconsistent entry", "the archive ends inside the entry"}) {
        if (what.starts_with(kind)) {
            return kind;
        }
    }
    return "not by the archive layer";
}

class Pk3Corruption : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("dsoc_pk3_corruption_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
        content_ = test::small_map_writer().build();
    }
    void TearDown() override {
        for (const auto& [kind, t] : tallies_) {
            std::cout << "pk3 corpus: " << kind << ": " << t.archives << " archives, " << t.loaded
                      << " loaded, " << (t.archives - t.loaded) << " refused";
            for (const auto& [reason, n] : t.by_reason) {
                std::cout << " (" << reason << ": " << n << ")";
            }
            std::cout << "\n";
        }
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }

    /// Writes `bytes` as an archive and loads the map in it as a server would; records
    /// the outcome under `kind` and checks that a refusal names archive and entry.
    void expect_refused(const std::string& kind, const std::vector<std::byte>& bytes,
                        const std::string& entry = kEntry) {
        const fs::path path = dir_ / ("case" + std::to_string(next_++) + ".pk3");
        test::write_file(path, bytes);
        Tally& t = tallies_[kind];
        ++t.archives;
        const auto map = load_map(path.string(), MapSearch{});
        if (map.ok()) {
            ++t.loaded;
            ADD_FAILURE() << kind << ": " << path << " loaded (" << map->spawn_points.size()
                          << " spawn points)";
            return;
        }
        const LoadError& e = map.error();
        const std::string reason = reason_kind(e.what);
        ++t.by_reason[reason];
        // Damage is caught where it is, not by luck further on (the BSP parser).
        EXPECT_NE(reason, "not by the archive layer") << kind << ": " << e.message();
        EXPECT_EQ(e.file, path.string()) << e.message();
        // Refusals when opening the archive come before any entry is looked at.
        if (!e.what.starts_with("cannot open archive")) {
            EXPECT_EQ(e.lump, entry) << e.message();
        }
    }

    /// Like expect_refused(), but loading is allowed when the entry's bytes are exactly
    /// the intact content (damage that changes nothing read); counted as "identical".
    void expect_identical_or_refused(const std::string& kind, const std::vector<std::byte>& bytes) {
        const fs::path path = dir_ / ("case" + std::to_string(next_++) + ".pk3");
        test::write_file(path, bytes);
        const auto read = read_pk3_entry(path, kEntry);
        if (read.ok()) {
            Tally& t = tallies_[kind];
            ++t.archives;
            ++t.loaded;
            ++t.by_reason["loaded with identical bytes"];
            EXPECT_EQ(read.value(), content_) << kind << ": " << path << " read different bytes";
            return;
        }
        expect_refused(kind, bytes);
    }

    /// The last refusal reason recorded for `kind` (for kinds with one archive).
    std::string only_reason(const std::string& kind) {
        const Tally& t = tallies_[kind];
        return t.by_reason.size() == 1 ? t.by_reason.begin()->first : std::string("mixed");
    }

    [[nodiscard]] ZipLayout deflated() const {
        return test::write_zip(test::make_entry(kEntry, content_, 8));
    }
    [[nodiscard]] ZipLayout stored() const {
        return test::write_zip(test::make_entry(kEntry, content_, 0));
    }

    fs::path dir_;
    std::vector<std::byte> content_;
    std::map<std::string, Tally> tallies_;
    int next_ = 0;
};

TEST_F(Pk3Corruption, IntactArchivesLoad) {
    for (const ZipLayout& zip : {deflated(), stored()}) {
        const fs::path path = dir_ / "intact.pk3";
        test::write_file(path, zip.bytes);
        const auto bytes = read_pk3_entry(path, kEntry);
        ASSERT_TRUE(bytes.ok()) << bytes.error().message();
        EXPECT_EQ(bytes.value(), content_);
        const auto map = load_map(path.string(), MapSearch{});
        ASSERT_TRUE(map.ok()) << map.error().message();
        EXPECT_EQ(map->spawn_points.size(), 1u);
    }
}

TEST_F(Pk3Corruption, BitFlipsInCompressedDataAreRefused) {
    const ZipLayout intact = deflated();
    const std::size_t size = intact.central_header - intact.data;
    ASSERT_GT(size, 16u);
    for (std::size_t i = 0; i < size; ++i) { // every byte of the deflate stream, one bit each
        ZipLayout zip = intact;
        zip.bytes[zip.data + i] ^= std::byte{static_cast<unsigned char>(1u << (i % 8))};
        if (i == 0) {
            // Bit 0 is deflate's "last block" flag: cleared, the stream decodes to the very
            // same bytes (CRC-32 and size match) and then merely lacks an end, which libzip
            // does not report. Harmless: never a different map. Anything else is refused.
            expect_identical_or_refused("bit flip in deflated data", zip.bytes);
            continue;
        }
        expect_refused("bit flip in deflated data", zip.bytes);
    }
}

TEST_F(Pk3Corruption, BitFlipsInStoredDataAreCrcMismatches) {
    const ZipLayout intact = stored();
    for (std::size_t i = 0; i < content_.size(); i += 7) {
        ZipLayout zip = intact;
        zip.bytes[zip.data + i] ^= std::byte{static_cast<unsigned char>(1u << (i % 8))};
        expect_refused("bit flip in stored data", zip.bytes);
    }
    EXPECT_EQ(only_reason("bit flip in stored data"), "CRC-32 mismatch");
}

TEST_F(Pk3Corruption, WrongCrcInBothHeadersIsACrcMismatch) {
    for (const ZipLayout& intact : {deflated(), stored()}) {
        ZipLayout zip = intact;
        zip.set_both(ZipLayout::kLocalCrc, ZipLayout::kCentralCrc,
                     zip.read_u32(zip.local_header + ZipLayout::kLocalCrc) ^ 0x00010000u);
        expect_refused("wrong CRC-32 declared", zip.bytes);
    }
    EXPECT_EQ(only_reason("wrong CRC-32 declared"), "CRC-32 mismatch");
}

TEST_F(Pk3Corruption, WrongDeclaredSizesAreSizeMismatches) {
    const auto real = static_cast<std::uint32_t>(content_.size());
    for (const ZipLayout& intact : {deflated()}) {
        for (const std::uint32_t declared : {real - 1, real - 100, real + 1, real + 100}) {
            ZipLayout zip = intact;
            zip.set_both(ZipLayout::kLocalSize, ZipLayout::kCentralSize, declared);
            expect_refused("wrong uncompressed size declared", zip.bytes);
        }
    }
    EXPECT_EQ(only_reason("wrong uncompressed size declared"), "size mismatch");
}

TEST_F(Pk3Corruption, TruncatedEntriesAreRefused) {
    // The entry's data cut short, the archive otherwise consistent: its headers declare
    // the shorter compressed size but the original uncompressed size and CRC-32.
    for (const std::uint16_t method : {std::uint16_t{8}, std::uint16_t{0}}) {
        ZipEntry entry = test::make_entry(kEntry, content_, method);
        for (const double kept : {0.0, 0.25, 0.5, 0.9}) {
            ZipEntry cut = entry;
            cut.data.resize(
                static_cast<std::size_t>(kept * static_cast<double>(entry.data.size())));
            expect_refused("truncated entry", test::write_zip(cut).bytes);
        }
    }
}

TEST_F(Pk3Corruption, TruncatedArchivesAreRefused) {
    const ZipLayout intact = deflated();
    for (std::size_t eighth = 1; eighth < 8; ++eighth) {
        std::vector<std::byte> cut = intact.bytes;
        cut.resize(cut.size() * eighth / 8);
        expect_refused("truncated archive", cut);
    }
    std::vector<std::byte> last_byte_gone = intact.bytes;
    last_byte_gone.pop_back();
    expect_refused("truncated archive", last_byte_gone);
    EXPECT_EQ(only_reason("truncated archive"), "cannot open archive");
}

TEST_F(Pk3Corruption, HeadersThatDisagreeAreRefused) {
    // Only the central directory altered: the local header still holds the truth.
    for (const std::size_t field :
         {ZipLayout::kCentralCrc, ZipLayout::kCentralSize, ZipLayout::kCentralCompressedSize}) {
        ZipLayout zip = deflated();
        zip.write_u32(zip.central_header + field, zip.read_u32(zip.central_header + field) + 1);
        expect_refused("central directory disagrees with local header", zip.bytes);
    }
}

/// The raw (still compressed) entry of `map` in the OpenArena pak, with its CRC-32
/// and sizes, ready to be written into an archive of its own.
ZipEntry raw_entry(zip_t* pak, const std::string& map) {
    ZipEntry e;
    e.name = "maps/" + map + ".bsp";
    const zip_int64_t index = zip_name_locate(pak, e.name.c_str(), 0);
    zip_stat_t st;
    if (index < 0 || zip_stat_index(pak, static_cast<zip_uint64_t>(index), 0, &st) != 0) {
        ADD_FAILURE() << "cannot find " << e.name;
        return e;
    }
    e.method = static_cast<std::uint16_t>(st.comp_method);
    e.crc = st.crc;
    e.size = static_cast<std::uint32_t>(st.size);
    e.data.resize(st.comp_size);
    zip_file_t* file = zip_fopen_index(pak, static_cast<zip_uint64_t>(index), ZIP_FL_COMPRESSED);
    if (file == nullptr ||
        zip_fread(file, e.data.data(), e.data.size()) != static_cast<zip_int64_t>(st.comp_size)) {
        ADD_FAILURE() << "cannot read " << e.name;
    }
    if (file != nullptr) {
        zip_fclose(file);
    }
    return e;
}

TEST_F(Pk3Corruption, BitFlipsInRealMapsAreRefused) {
    DSOC_REQUIRE_OPENARENA();
    int code = 0;
    zip_t* pak = zip_open(test::kOpenArenaPak.c_str(), ZIP_RDONLY, &code);
    ASSERT_NE(pak, nullptr);
    // The six smallest maps of the pak (by compressed size), as single-map archives.
    for (const char* map :
         {"oa_ctf2", "oa_bases5", "q3dm6ish", "oa_bases3cl", "am_galmevish", "ps37ctf"}) {
        const ZipEntry entry = raw_entry(pak, map);
        const ZipLayout intact = test::write_zip(entry);
        const fs::path path = dir_ / (std::string(map) + ".pk3");
        test::write_file(path, intact.bytes);
        const auto loaded = load_map(path.string(), MapSearch{});
        ASSERT_TRUE(loaded.ok()) << loaded.error().message();
        EXPECT_FALSE(loaded->spawn_points.empty()) << map;
        // Three flips per map, a different bit each, spread over the compressed data.
        for (const std::size_t quarter : {1u, 2u, 3u}) {
            ZipLayout zip = intact;
            zip.bytes[zip.data + entry.data.size() * quarter / 4] ^=
                std::byte{static_cast<unsigned char>(1u << (quarter * 2))};
            expect_refused("bit flip in a real map's deflated data", zip.bytes, entry.name);
        }
    }
    zip_discard(pak);
}

} // namespace
} // namespace dsoc::maps
