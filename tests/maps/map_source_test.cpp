// Finding maps: by name in archives, by path, generators; archive errors.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/pk3.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace dsoc::maps {
namespace {

namespace fs = std::filesystem;

fs::path temp_file(const std::string& name, const std::string& content) {
    const fs::path path = fs::temp_directory_path() / ("dsoc_maps_test_" + name);
    std::ofstream(path, std::ios::binary) << content;
    return path;
}

TEST(MapSource, CorruptArchiveIsAnError) {
    const fs::path path = temp_file("corrupt.pk3", std::string("PK\x03\x04 this is not a zip"));
    const auto result = read_pk3_entry(path, "maps/x.bsp");
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error().file, path.string());
    EXPECT_NE(result.error().what.find("cannot open archive"), std::string::npos)
        << result.error().message();
    MapSearch search{{path}};
    const auto map = load_map("oa_dm4", search);
    ASSERT_FALSE(map.ok());
    EXPECT_NE(map.error().what.find("no map of that name"), std::string::npos);
    fs::remove(path);
}

TEST(MapSource, MissingArchiveAndMissingEntry) {
    const auto missing = read_pk3_entry("/nonexistent/dsoc.pk3", "maps/x.bsp");
    ASSERT_FALSE(missing.ok());
    DSOC_REQUIRE_OPENARENA();
    const auto entry = read_pk3_entry(test::kOpenArenaPak, "maps/no_such_map.bsp");
    ASSERT_FALSE(entry.ok());
    EXPECT_EQ(entry.error().lump, "maps/no_such_map.bsp");
    EXPECT_NE(entry.error().what.find("no such entry"), std::string::npos);
}

TEST(MapSource, FindsOpenArenaMapsByName) {
    DSOC_REQUIRE_OPENARENA();
    const MapSearch search{{test::kOpenArenaPak}};
    const auto map = load_map("OA_DM4", search); // names match case-insensitively
    ASSERT_TRUE(map.ok()) << map.error().message();
    EXPECT_FALSE(map->occluders.empty());
    const auto bsp = find_q3_bsp("oa_dm4", search);
    ASSERT_TRUE(bsp.ok()) << bsp.error().message();
    EXPECT_EQ(bsp->brushes.size(), map->stats.brushes_total);
    const auto missing = load_map("no_such_map", search);
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().what.find("maps/no_such_map.bsp"), std::string::npos)
        << missing.error().message();
    EXPECT_EQ(list_maps(search).size(), 50u);
    const auto whole_pak = load_map(test::kOpenArenaPak.string(), search);
    ASSERT_FALSE(whole_pak.ok());
    EXPECT_NE(whole_pak.error().what.find("holds 50 maps"), std::string::npos);
}

TEST(MapSource, LoadsPlainBspAndTextFiles) {
    const auto bytes = test::small_map_writer().build();
    const fs::path bsp = temp_file(
        "small.bsp", std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
    const auto from_bsp = load_map(bsp.string(), MapSearch{});
    ASSERT_TRUE(from_bsp.ok()) << from_bsp.error().message();
    EXPECT_EQ(from_bsp->name, "dsoc_maps_test_small");
    EXPECT_EQ(from_bsp->occluders.size(), 1u);

    const fs::path text = temp_file("small.dsocmap", "dsoc-map 1\nbox solid 0 0 0 8 8 8\n");
    const auto from_text = load_map(text.string(), MapSearch{});
    ASSERT_TRUE(from_text.ok()) << from_text.error().message();
    EXPECT_EQ(from_text->occluders.size(), 1u);

    const fs::path bad = temp_file("bad.bsp", "IBSP");
    const auto from_bad = load_map(bad.string(), MapSearch{});
    ASSERT_FALSE(from_bad.ok());
    EXPECT_EQ(from_bad.error().file, bad.string());
    fs::remove(bsp);
    fs::remove(text);
    fs::remove(bad);
}

TEST(MapSource, Generators) {
    const auto city = load_map("gen:city:7", MapSearch{});
    ASSERT_TRUE(city.ok());
    EXPECT_GT(city->occluders.size(), 64u);
    const auto rooms = load_map("gen:rooms", MapSearch{});
    ASSERT_TRUE(rooms.ok());
    EXPECT_FALSE(load_map("gen:castle", MapSearch{}).ok());
    EXPECT_FALSE(load_map("gen:city:x", MapSearch{}).ok());
}

} // namespace
} // namespace dsoc::maps
