// The BSP parser and the Quake 3 -> Map rules, on small files built in memory: a
// valid one, and one corruption at a time, each of which must give an error that
// names the lump and never crash.

#include "dsoc/maps/q3_bsp.hpp"
#include "dsoc/maps/q3_map.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace dsoc::maps {
namespace {

using q3::Lump;
using test::BspWriter;
using test::small_map_writer;

Result<q3::Q3Bsp> parse(const std::vector<std::byte>& bytes) {
    return q3::parse_q3_bsp(bytes, "test.bsp");
}

void expect_error(const std::vector<std::byte>& bytes, const std::string& lump,
                  const std::string& fragment) {
    const auto result = parse(bytes);
    ASSERT_FALSE(result.ok()) << "expected an error mentioning " << fragment;
    EXPECT_EQ(result.error().file, "test.bsp");
    EXPECT_EQ(result.error().lump, lump) << result.error().message();
    EXPECT_NE(result.error().what.find(fragment), std::string::npos) << result.error().message();
}

void set_i32(std::vector<std::byte>& bytes, std::size_t offset, std::int32_t value) {
    std::memcpy(bytes.data() + offset, &value, 4);
}

std::size_t lump_offset(const std::vector<std::byte>& bytes, Lump lump) {
    std::int32_t offset = 0;
    std::memcpy(&offset, bytes.data() + 8 + 8 * static_cast<int>(lump), 4);
    return static_cast<std::size_t>(offset);
}

TEST(Q3Bsp, ParsesValidSmallMap) {
    const auto result = parse(small_map_writer().build());
    ASSERT_TRUE(result.ok()) << result.error().message();
    const q3::Q3Bsp& bsp = result.value();
    EXPECT_EQ(bsp.shaders.size(), 4u);
    EXPECT_EQ(bsp.shaders[2].name, "textures/common/caulk");
    EXPECT_EQ(bsp.brushes.size(), 4u);
    EXPECT_EQ(bsp.brush_sides.size(), 24u);
    EXPECT_EQ(bsp.planes.size(), 24u);
    EXPECT_EQ(bsp.models.size(), 1u);
    EXPECT_EQ(bsp.raw_lump(Lump::planes).size(), 24u * 16u);
    EXPECT_EQ(bsp.visibility.num_clusters, 0);
}

TEST(Q3Map, AppliesOcclusionAndCollisionRules) {
    const auto bsp = parse(small_map_writer().build());
    ASSERT_TRUE(bsp.ok());
    const auto map = map_from_q3_bsp(bsp.value(), "small");
    ASSERT_TRUE(map.ok()) << map.error().message();
    // Only the floor occludes: glass is translucent, caulk draws nothing, clip is not solid.
    ASSERT_EQ(map->occluders.size(), 1u);
    EXPECT_FLOAT_EQ(map->occluders[0].bounds().max.z, 0.0f);
    EXPECT_EQ(map->collision_brushes.size(), 4u);
    EXPECT_EQ(map->stats.translucent_skipped, 1u);
    EXPECT_EQ(map->stats.nodraw_skipped, 1u);
    EXPECT_EQ(map->stats.degenerate.total(), 0u);
    ASSERT_EQ(map->spawn_points.size(), 1u);
    EXPECT_EQ(map->spawn_points[0].origin, glm::vec3(0, 0, 40));
    EXPECT_FLOAT_EQ(map->spawn_points[0].yaw_degrees, 90.0f);
    EXPECT_EQ(map->bounds.min, glm::vec3(-256, -256, -16));
    EXPECT_EQ(map->bounds.max, glm::vec3(256, 256, 256));
    for (const CollisionBrush& brush : map->collision_brushes) {
        EXPECT_GE(brush.planes.size(), 6u);
    }
}

TEST(Q3Map, SkipsDegenerateBrushesByReason) {
    BspWriter w = small_map_writer();
    // A fifth brush with 3 sides (too few planes) and a sixth that is empty
    // (x <= 0 and x >= 10).
    w.put_i32s(Lump::brush_sides, {0, 0, 1, 0, 4, 0});
    w.put_i32s(Lump::brushes, {24, 3, 0});
    w.put_f32s(Lump::planes, {1, 0, 0, 0, -1, 0, 0, -10});
    w.put_i32s(Lump::brush_sides, {24, 0, 25, 0, 2, 0, 3, 0, 4, 0, 5, 0});
    w.put_i32s(Lump::brushes, {27, 6, 0});
    w.lumps[static_cast<int>(Lump::models)].clear();
    w.put_f32s(Lump::models, {-256, -256, -16, 256, 256, 256});
    w.put_i32s(Lump::models, {0, 0, 0, 6});
    const auto bsp = parse(w.build());
    ASSERT_TRUE(bsp.ok()) << bsp.error().message();
    const auto map = map_from_q3_bsp(bsp.value(), "small");
    ASSERT_TRUE(map.ok());
    EXPECT_EQ(map->stats.degenerate.too_few_planes, 1u);
    EXPECT_EQ(map->stats.degenerate.empty, 1u);
    EXPECT_EQ(map->collision_brushes.size(), 4u);
    EXPECT_EQ(map->occluders.size(), 1u);
}

TEST(Q3Bsp, RejectsShortHeader) {
    std::vector<std::byte> bytes(20, std::byte{0});
    const auto result = parse(bytes);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error().lump, "header");
    EXPECT_NE(result.error().message().find("test.bsp"), std::string::npos);
}

TEST(Q3Bsp, RejectsWrongMagicAndVersion) {
    BspWriter w = small_map_writer();
    w.magic = "VBSP";
    expect_error(w.build(), "header", "magic");
    w = small_map_writer();
    w.version = 47;
    expect_error(w.build(), "header", "version 47");
}

TEST(Q3Bsp, RejectsLumpOutOfRange) {
    auto bytes = small_map_writer().build();
    set_i32(bytes, 8 + 8 * 2 + 4, 1 << 30); // planes length
    expect_error(bytes, "planes (lump 2)", "past the end");
    bytes = small_map_writer().build();
    set_i32(bytes, 8 + 8 * 9, -4); // brush sides offset
    expect_error(bytes, "brush sides (lump 9)", "negative");
}

TEST(Q3Bsp, RejectsLengthsThatDoNotDivide) {
    BspWriter w = small_map_writer();
    w.put(Lump::brushes, std::int32_t{7});
    expect_error(w.build(), "brushes (lump 8)", "not a multiple of the 12-byte");
}

TEST(Q3Bsp, RejectsIndexesOutOfRange) {
    auto bytes = small_map_writer().build();
    set_i32(bytes, lump_offset(bytes, Lump::brush_sides), 999); // side 0 plane
    expect_error(bytes, "brush sides (lump 9)", "plane index 999");

    bytes = small_map_writer().build();
    set_i32(bytes, lump_offset(bytes, Lump::brush_sides) + 4, -1); // side 0 shader
    expect_error(bytes, "brush sides (lump 9)", "shader index -1");

    bytes = small_map_writer().build();
    set_i32(bytes, lump_offset(bytes, Lump::brushes) + 4, 100); // brush 0 side count
    expect_error(bytes, "brushes (lump 8)", "out of range");

    bytes = small_map_writer().build();
    set_i32(bytes, lump_offset(bytes, Lump::models) + 36, 5); // model 0 brush count
    expect_error(bytes, "models (lump 7)", "brushes [0, +5)");
}

TEST(Q3Bsp, RejectsMissingWorldModel) {
    BspWriter w = small_map_writer();
    w.lumps[static_cast<int>(Lump::models)].clear();
    expect_error(w.build(), "models (lump 7)", "no models");
}

TEST(Q3Bsp, RejectsNodeCyclesAndBadLeafs) {
    BspWriter w = small_map_writer();
    w.put_i32s(Lump::leafs, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
    // Node 0 points back at itself: a cycle a tree walk would never leave.
    w.put_i32s(Lump::nodes, {0, 0, -1, 0, 0, 0, 0, 0, 0});
    expect_error(w.build(), "nodes (lump 3)", "child 0");

    w = small_map_writer();
    w.put_i32s(Lump::leafs, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 3, 1}); // leaf brushes [3, +1)
    expect_error(w.build(), "leafs (lump 4)", "leaf brushes");

    w = small_map_writer();
    w.put_i32s(Lump::leaf_brushes, {4});
    expect_error(w.build(), "leaf brushes (lump 6)", "brush index 4");
}

TEST(Q3Bsp, RejectsInconsistentVisibility) {
    BspWriter w = small_map_writer();
    w.put_i32s(Lump::visibility, {1000, 1000});
    expect_error(w.build(), "visibility (lump 16)", "need");
    w = small_map_writer();
    w.put_i32s(Lump::visibility, {64, 1}); // 64 clusters cannot fit in 8 bits a row
    for (int i = 0; i < 64; ++i) {
        w.put(Lump::visibility, std::uint8_t{0xff});
    }
    expect_error(w.build(), "visibility (lump 16)", "cannot hold");
}

TEST(Q3Map, BadSpawnOriginIsAnError) {
    BspWriter w = small_map_writer();
    w.lumps[0].clear();
    const std::string text = "{ \"classname\" \"info_player_start\" \"origin\" \"1 nan 3\" }";
    for (const char c : text) {
        w.put(Lump::entities, c);
    }
    const auto bsp = parse(w.build());
    ASSERT_TRUE(bsp.ok());
    const auto map = map_from_q3_bsp(bsp.value(), "x");
    ASSERT_FALSE(map.ok());
    EXPECT_EQ(map.error().lump, "entities (lump 0)");
    EXPECT_NE(map.error().what.find("origin"), std::string::npos);
}

TEST(Q3Map, UnterminatedEntityIsAnError) {
    BspWriter w = small_map_writer();
    w.lumps[0].clear();
    for (const char c : std::string("{ \"classname\" \"worldspawn\" ")) {
        w.put(Lump::entities, c);
    }
    const auto bsp = parse(w.build());
    ASSERT_TRUE(bsp.ok());
    const auto map = map_from_q3_bsp(bsp.value(), "x");
    ASSERT_FALSE(map.ok());
    EXPECT_NE(map.error().what.find("unterminated"), std::string::npos) << map.error().message();
}

TEST(Q3Bsp, EveryTruncationFailsCleanly) {
    const auto bytes = small_map_writer().build();
    for (std::size_t size = 0; size < bytes.size(); size += 7) {
        const std::vector<std::byte> cut(bytes.begin(), bytes.begin() + static_cast<long>(size));
        EXPECT_FALSE(parse(cut).ok()) << "truncated to " << size << " bytes";
    }
}

} // namespace
} // namespace dsoc::maps
