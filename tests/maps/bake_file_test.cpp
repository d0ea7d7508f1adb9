// The .dsocbake file and the cache: a table survives the round trip bit for bit;
// truncated, corrupt, wrong-version and wrong-map files are each refused with a
// message naming the file and what is wrong; the cache rebakes what it refuses and
// bakes anew for a changed map.

#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/maps/bake_file.hpp"
#include "dsoc/maps/map_source.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace dsoc::maps {
namespace {

namespace fs = std::filesystem;

const test::Corridor& rooms() {
    return test::shared_corridor();
}

BakeRequest small_request(const fs::path& dir) {
    BakeRequest r;
    r.config.cell_size = 128.0f; // coarse: these tests are about the files, not the table
    r.config.threads = 2;
    r.dir = dir;
    return r;
}

class BakeFileTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ =
            fs::temp_directory_path() /
            ("dsoc-bake-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

std::vector<std::byte> read_all(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::vector<char> raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::byte> out(raw.size());
    std::memcpy(out.data(), raw.data(), raw.size());
    return out;
}

void write_all(const fs::path& p, const std::vector<std::byte>& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
}

TEST_F(BakeFileTest, TheCacheBakesOnceThenLoadsTheSameBits) {
    const auto first = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(first.ok()) << first.error().message();
    EXPECT_FALSE(first->from_cache);
    EXPECT_TRUE(first->write_problem.empty()) << first->write_problem;
    EXPECT_TRUE(fs::exists(first->file));
    EXPECT_GT(first->table->hidden_pairs(), 0u); // something is culled
    const auto second = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(second.ok());
    EXPECT_TRUE(second->from_cache);
    EXPECT_TRUE(second->cache_problem.empty());
    ASSERT_EQ(first->table->open_cells(), second->table->open_cells());
    ASSERT_TRUE(*first->table == *second->table); // the same compressed rows
}

TEST_F(BakeFileTest, EveryKindOfDamageIsRefusedNamingTheFileAndWhat) {
    const auto baked = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(baked.ok());
    const auto good = read_all(baked->file);
    ASSERT_TRUE(decode_bake(good, "good", baked->key).ok());
    struct Damage {
        const char* kind;
        std::vector<std::byte> bytes;
        const char* expect; ///< in the message
    };
    std::vector<Damage> cases;
    cases.push_back({"empty", {}, "truncated"});
    cases.push_back({"header cut", {good.begin(), good.begin() + 40}, "truncated"});
    cases.push_back({"rows cut", {good.begin(), good.end() - 9}, "truncated"});
    auto longer = good;
    longer.push_back(std::byte{0});
    cases.push_back({"trailing byte", longer, "trailing bytes"});
    auto flipped = good;
    flipped[flipped.size() / 2 + 3] ^= std::byte{0x10};
    cases.push_back({"bit flip in the rows", flipped, "checksum"});
    auto flipped_head = good;
    flipped_head[30] ^= std::byte{0x01}; // the grid origin
    cases.push_back({"bit flip in the header", flipped_head, "checksum"});
    auto magic = good;
    magic[0] = std::byte{'X'};
    cases.push_back({"magic", magic, "not a .dsocbake file"});
    auto version = good;
    version[8] = std::byte{99};
    cases.push_back({"version", version, "format version 99"});
    auto dims = good;
    const std::int32_t huge = 1 << 30;
    std::memcpy(dims.data() + 40, &huge, 4);
    cases.push_back({"absurd grid", dims, "grid dimensions"});
    // Three sides whose product is 0 modulo 2^64 (found by fuzz_bake): the reader used
    // to multiply them at once, and the wrapped count passed its limit.
    auto wrapping = good;
    for (int axis = 0; axis < 3; ++axis) {
        const std::int32_t side = (0x2A + 2 * axis) << 24;
        std::memcpy(wrapping.data() + 40 + 4 * axis, &side, 4);
    }
    cases.push_back({"grid whose cell count wraps", wrapping, "grid dimensions"});
    auto sparse = good; // a grid far larger than its open cells (allocation guard)
    const std::int32_t side = 200;
    for (int axis = 0; axis < 3; ++axis) {
        std::memcpy(sparse.data() + 40 + 4 * axis, &side, 4);
    }
    cases.push_back({"grid much larger than its open cells", sparse, "per open cell"});
    // Two open cells swapped, the checksum made good again: the order is checked too.
    auto swapped = good;
    std::swap_ranges(swapped.begin() + 80, swapped.begin() + 84, swapped.begin() + 84);
    const auto resum = [](std::vector<std::byte>& bytes) {
        const std::span<const std::byte> all(bytes);
        const std::uint64_t sum = bake_checksum(all.subspan(72), bake_checksum(all.first(64)));
        std::memcpy(bytes.data() + 64, &sum, 8);
    };
    resum(swapped);
    cases.push_back({"open cells out of block order", swapped, "not in block order"});
    // The last literal word zeroed (a literal must be neither all hidden nor all
    // visible), the checksum made good again: the rows' rules are checked too.
    std::uint64_t literal_count = 0;
    std::memcpy(&literal_count, good.data() + 72, 8);
    ASSERT_GT(literal_count, 0u);
    auto zero_literal = good;
    std::fill(zero_literal.end() - 8, zero_literal.end(), std::byte{0});
    resum(zero_literal);
    cases.push_back({"a literal word of zeros", zero_literal, "a literal that is all hidden"});
    auto huge_literals = good;
    const std::uint64_t absurd = std::uint64_t{1} << 60;
    std::memcpy(huge_literals.data() + 72, &absurd, 8);
    resum(huge_literals);
    cases.push_back({"absurd literal count", huge_literals, "literal words: over the limit"});
    for (const Damage& d : cases) {
        const auto r = decode_bake(d.bytes, "t.dsocbake", baked->key);
        ASSERT_FALSE(r.ok()) << d.kind << " was accepted";
        const std::string m = r.error().message();
        EXPECT_NE(m.find("t.dsocbake"), std::string::npos) << d.kind << ": " << m;
        EXPECT_NE(m.find(d.expect), std::string::npos) << d.kind << ": " << m;
    }
    // A good file of another map (or other settings) is refused by its key.
    const auto other = decode_bake(good, "t.dsocbake", baked->key ^ 1u);
    ASSERT_FALSE(other.ok());
    EXPECT_NE(other.error().message().find("another map"), std::string::npos);
}

TEST_F(BakeFileTest, TheCacheRefusesADamagedFileInOneLineAndBakesAgain) {
    const auto baked = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(baked.ok());
    auto bytes = read_all(baked->file);
    bytes[bytes.size() - 20] ^= std::byte{0x04};
    write_all(baked->file, bytes);
    const auto again = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(again.ok());
    EXPECT_FALSE(again->from_cache);
    EXPECT_NE(again->cache_problem.find(baked->file.string()), std::string::npos)
        << again->cache_problem;
    EXPECT_NE(again->cache_problem.find("checksum"), std::string::npos) << again->cache_problem;
    EXPECT_EQ(again->cache_problem.find('\n'), std::string::npos);
    // The rebaked file is good again.
    EXPECT_TRUE(read_bake_file(again->file, again->key).ok());
    // A truncated file: the same.
    fs::resize_file(again->file, 100);
    const auto third = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(third.ok());
    EXPECT_FALSE(third->from_cache);
    EXPECT_NE(third->cache_problem.find("truncated"), std::string::npos) << third->cache_problem;
}

TEST_F(BakeFileTest, AChangedMapIsBakedAnewNotServedTheOldTable) {
    const auto before = load_or_bake(rooms().map, *rooms().scene, small_request(dir_));
    ASSERT_TRUE(before.ok());
    Map changed = rooms().map;
    changed.occluders.pop_back(); // one wall fewer
    const auto scene = visibility::OccluderScene::build(changed.occluders);
    const auto after = load_or_bake(changed, *scene, small_request(dir_));
    ASSERT_TRUE(after.ok());
    EXPECT_NE(before->key, after->key);
    EXPECT_FALSE(after->from_cache);
    // The old map's file planted under the new key's name is refused as another map's.
    fs::copy_file(before->file, after->file, fs::copy_options::overwrite_existing);
    const auto planted = load_or_bake(changed, *scene, small_request(dir_));
    ASSERT_TRUE(planted.ok());
    EXPECT_FALSE(planted->from_cache);
    EXPECT_NE(planted->cache_problem.find("another map"), std::string::npos)
        << planted->cache_problem;
}

TEST(BakeFile, ATableWithNoOpenCellsSurvivesTheRoundTrip) {
    visibility::CellGrid grid;
    grid.cell_size = 32.0f;
    grid.dims = {4, 4, 2};
    const visibility::CellVisibilityTable empty(grid, {});
    const auto decoded = decode_bake(encode_bake(empty, 42), "empty", 42);
    ASSERT_TRUE(decoded.ok()) << decoded.error().message();
    EXPECT_EQ(decoded->open_count(), 0u);
    EXPECT_EQ(decoded->grid().dims, grid.dims);
}

TEST_F(BakeFileTest, AFinerTableInTheCacheIsTakenWithoutBakingAgain) {
    // Baked under a budget that keeps the asked-for cells; then asked for with a budget
    // that would make a bake grow them: the finer table on disk is served as it is.
    auto roomy = small_request(dir_);
    const auto baked = load_or_bake(rooms().map, *rooms().scene, roomy);
    ASSERT_TRUE(baked.ok()) << baked.error().message();
    ASSERT_FALSE(baked->from_cache);
    auto tight = small_request(dir_);
    tight.max_table_bytes = 8; // a bake now would grow the cells to the last grid
    const auto coarse = bake_grid(rooms().map, *rooms().scene, tight.config.cell_size,
                                  tight.max_table_bytes, std::nullopt);
    ASSERT_GT(coarse.cell_size, baked->table->grid().cell_size);
    const auto again = load_or_bake(rooms().map, *rooms().scene, tight);
    ASSERT_TRUE(again.ok());
    EXPECT_TRUE(again->from_cache);
    EXPECT_EQ(again->file, baked->file);
    EXPECT_TRUE(*again->table == *baked->table);
    // With the file gone, the tight budget bakes its own (coarser) grid.
    fs::remove(baked->file);
    const auto rebaked = load_or_bake(rooms().map, *rooms().scene, tight);
    ASSERT_TRUE(rebaked.ok());
    EXPECT_FALSE(rebaked->from_cache);
    EXPECT_EQ(rebaked->table->grid().cell_size, coarse.cell_size);
}

TEST(BakeKey, TheMapsPartOnceGivesTheSameKeys) {
    const Map& map = rooms().map;
    visibility::CellBakeConfig config;
    const std::uint64_t of_map = bake_key_of_map(map);
    for (const float size : {32.0f, 40.0f, 128.0f}) {
        const auto grid = visibility::CellGrid::covering(map.bounds, size);
        EXPECT_EQ(bake_key(of_map, grid, config, std::nullopt),
                  bake_key(map, grid, config, std::nullopt));
    }
    EXPECT_NE(
        bake_key(of_map, visibility::CellGrid::covering(map.bounds, 32.0f), config, std::nullopt),
        bake_key(of_map, visibility::CellGrid::covering(map.bounds, 40.0f), config, std::nullopt));
}

TEST(BakeKey, DependsOnTheSettingsThatChangeTheTableOnly) {
    const Map& map = rooms().map;
    const auto grid = visibility::CellGrid::covering(map.bounds, 128.0f);
    visibility::CellBakeConfig a;
    a.cell_size = 128.0f;
    visibility::CellBakeConfig b = a;
    b.threads = 7; // not part of the result
    EXPECT_EQ(bake_key(map, grid, a, std::nullopt), bake_key(map, grid, b, std::nullopt));
    b.portal_depth = 1;
    EXPECT_NE(bake_key(map, grid, a, std::nullopt), bake_key(map, grid, b, std::nullopt));
    // The space the table covers is part of what it says.
    const PlayerSpace low{0.7f, 100.0f, 32.0f};
    PlayerSpace high = low;
    high.height = 200.0f;
    EXPECT_NE(bake_key(map, grid, a, std::nullopt), bake_key(map, grid, a, low));
    EXPECT_NE(bake_key(map, grid, a, low), bake_key(map, grid, a, high));
    EXPECT_EQ(bake_key(map, grid, a, low), bake_key(map, grid, a, PlayerSpace{low}));
}

/// The corridor with a floor under the left half of it: walkers can be only above that.
Map corridor_with_a_floor() {
    Map map = rooms().map;
    const visibility::Aabb& b = map.bounds;
    const visibility::Aabb floor{b.min, {b.center().x, b.max.y, b.min.z + 8.0f}};
    CollisionBrush brush;
    brush.bounds = floor;
    add_axial_bevels(brush.planes, floor);
    map.collision_brushes.push_back(brush);
    return map;
}

TEST_F(BakeFileTest, ATableWithUncoveredCellsSurvivesTheRoundTripAndItsDamageIsRefused) {
    const Map map = corridor_with_a_floor();
    auto request = small_request(dir_);
    request.player_space = PlayerSpace{0.7f, 70.0f, 0.0f};
    const auto baked = load_or_bake(map, *rooms().scene, request);
    ASSERT_TRUE(baked.ok()) << baked.error().message();
    const auto& table = *baked->table;
    ASSERT_GT(table.uncovered_cells().size(), 0u);
    ASSERT_GT(table.open_count(), 0u);
    EXPECT_EQ(baked->stats.uncovered_cells, table.uncovered_cells().size());
    // Only cells over the floor are covered.
    for (const std::uint32_t c : table.open_cells()) {
        const auto box = table.grid().cell_box(table.grid().coords(c));
        EXPECT_LE(box.min.x, map.bounds.center().x + 1.0f);
        EXPECT_LE(box.min.z, map.bounds.min.z + 8.0f + 70.0f + 1.0f);
    }
    const auto again = load_or_bake(map, *rooms().scene, request);
    ASSERT_TRUE(again.ok());
    EXPECT_TRUE(again->from_cache);
    EXPECT_TRUE(*again->table == table);
    // Without the space: another key, another file, no uncovered cells.
    request.player_space.reset();
    const auto whole = load_or_bake(map, *rooms().scene, request);
    ASSERT_TRUE(whole.ok());
    EXPECT_NE(whole->key, baked->key);
    EXPECT_TRUE(whole->table->uncovered_cells().empty());
    EXPECT_EQ(whole->table->open_count(), table.open_count() + table.uncovered_cells().size());

    const auto good = read_all(baked->file);
    const std::size_t bitmap_at = 80 + (table.open_count() * 4 + 7) / 8 * 8;
    const auto resum = [](std::vector<std::byte>& bytes) {
        const std::span<const std::byte> all(bytes);
        const std::uint64_t sum = bake_checksum(all.subspan(72), bake_checksum(all.first(64)));
        std::memcpy(bytes.data() + 64, &sum, 8);
    };
    const auto set_bit = [&](std::vector<std::byte>& bytes, std::uint64_t cell) {
        bytes[bitmap_at + cell / 8] |= std::byte{static_cast<unsigned char>(1u << (cell % 8))};
        resum(bytes);
    };
    auto both = good;
    set_bit(both, table.open_cells().front());
    const auto r1 = decode_bake(both, "t.dsocbake", baked->key);
    ASSERT_FALSE(r1.ok());
    EXPECT_NE(r1.error().message().find("both open and uncovered"), std::string::npos)
        << r1.error().message();
    const std::uint64_t cells = table.grid().cell_count();
    if (cells % 64 != 0) {
        auto past = good;
        set_bit(past, cells);
        const auto r2 = decode_bake(past, "t.dsocbake", baked->key);
        ASSERT_FALSE(r2.ok());
        EXPECT_NE(r2.error().message().find("past the last grid cell"), std::string::npos)
            << r2.error().message();
    }
}

} // namespace
} // namespace dsoc::maps
