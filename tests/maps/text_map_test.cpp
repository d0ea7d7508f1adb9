// Our text map format: parsing, kinds, round trip through format_text_map, and
// errors that name the line.

#include "dsoc/maps/map_spec.hpp"

#include <gtest/gtest.h>

namespace dsoc::maps {
namespace {

constexpr const char* kSample = R"(dsoc-map 1
# a floor, a glass pane, a caulk block, a clip wall and a wedge
name sample
box solid -512 -512 -16 512 512 0
box glass 100 -64 0 104 64 128
box caulk -200 -200 0 -150 -150 64
box clip -10 150 0 10 200 256
brush solid 5
plane 0 0 -1 0
plane -1 0 0 0
plane 0 -1 0 0
plane 0 1 0 64
plane 1 0 1 128   # slanted, normal need not be unit
spawn 0 0 25 90
spawn 200 200 25 0 team_CTF_redspawn
hazard -100 -100 -500 100 100 -400
)";

TEST(TextMap, ParsesSample) {
    const auto spec = parse_text_map(kSample, "sample.dsocmap");
    ASSERT_TRUE(spec.ok()) << spec.error().message();
    EXPECT_EQ(spec->name, "sample");
    ASSERT_EQ(spec->brushes.size(), 5u);
    EXPECT_EQ(spec->brushes[1].kind, BrushKind::glass);
    EXPECT_EQ(spec->brushes[4].planes.size(), 5u);
    ASSERT_EQ(spec->spawn_points.size(), 2u);
    EXPECT_FLOAT_EQ(spec->spawn_points[0].yaw_degrees, 90.0f);
    EXPECT_EQ(spec->spawn_points[1].classname, "team_CTF_redspawn");
    ASSERT_EQ(spec->hazards.size(), 1u);
    EXPECT_EQ(spec->hazards[0].bounds.min.z, -500.0f);

    const Map map = build_map(spec.value(), "sample.dsocmap");
    EXPECT_EQ(map.occluders.size(), 2u); // the floor and the wedge
    EXPECT_EQ(map.collision_brushes.size(), 5u);
    EXPECT_EQ(map.stats.translucent_skipped, 1u);
    EXPECT_EQ(map.stats.nodraw_skipped, 1u);
    EXPECT_EQ(map.collision_brushes[3].contents, contents_player_clip);
    // The wedge got its axial bevels: 5 planes + top (+z) bevel at least.
    EXPECT_GE(map.collision_brushes[4].planes.size(), 6u);
    EXPECT_NEAR(map.collision_brushes[4].bounds.max.z, 128.0f, 1e-3f);
}

TEST(TextMap, RoundTrips) {
    const auto spec = parse_text_map(kSample, "sample");
    ASSERT_TRUE(spec.ok());
    const std::string text = format_text_map(spec.value());
    const auto again = parse_text_map(text, "again");
    ASSERT_TRUE(again.ok()) << again.error().message();
    ASSERT_EQ(again->brushes.size(), spec->brushes.size());
    for (std::size_t i = 0; i < spec->brushes.size(); ++i) {
        EXPECT_EQ(again->brushes[i].kind, spec->brushes[i].kind);
        ASSERT_EQ(again->brushes[i].planes.size(), spec->brushes[i].planes.size());
        for (std::size_t p = 0; p < spec->brushes[i].planes.size(); ++p) {
            EXPECT_EQ(again->brushes[i].planes[p].normal, spec->brushes[i].planes[p].normal);
            EXPECT_EQ(again->brushes[i].planes[p].distance, spec->brushes[i].planes[p].distance);
        }
    }
    EXPECT_EQ(again->hazards.size(), 1u);
    EXPECT_EQ(format_text_map(again.value()), text);
}

struct BadCase {
    const char* text;
    const char* lump;
    const char* fragment;
};

TEST(TextMap, ErrorsNameTheLine) {
    const BadCase cases[] = {
        {"", "", "empty"},
        {"dsoc-map 2\n", "line 1", "header"},
        {"dsoc-map 1\nbox solid 0 0 0 1 1\n", "line 2", "box"},
        {"dsoc-map 1\nbox stone 0 0 0 1 1 1\n", "line 2", "box"},
        {"dsoc-map 1\nbox solid 0 0 0 1 nan 1\n", "line 2", "finite"},
        {"dsoc-map 1\nbox solid 0 0 0 1e9 1 1\n", "line 2", "finite"},
        {"dsoc-map 1\n\nbox solid 5 0 0 1 1 1\n", "line 3", "below max"},
        {"dsoc-map 1\nbrush solid 3\n", "line 2", "4 <= n <= 64"},
        {"dsoc-map 1\nbrush solid 100000\n", "line 2", "4 <= n <= 64"},
        {"dsoc-map 1\nbrush solid 4\nplane 1 0 0 1\n", "line 3", "ends inside a brush"},
        {"dsoc-map 1\nbrush solid 4\nplane 1 0 0\n", "line 3", "plane"},
        {"dsoc-map 1\nspawn 1 2\n", "line 2", "spawn"},
        {"dsoc-map 1\nteleport 1 2 3\n", "line 2", "unknown statement"},
        {"dsoc-map 1\nhazard 0 0 0 1 1\n", "line 2", "hazard"},
    };
    for (const BadCase& c : cases) {
        const auto result = parse_text_map(c.text, "bad.dsocmap");
        ASSERT_FALSE(result.ok()) << c.text;
        EXPECT_EQ(result.error().file, "bad.dsocmap");
        EXPECT_EQ(result.error().lump, c.lump) << result.error().message();
        EXPECT_NE(result.error().what.find(c.fragment), std::string::npos)
            << result.error().message();
    }
}

TEST(TextMap, DegenerateBrushesAreCountedNotFatal) {
    const auto spec = parse_text_map("dsoc-map 1\n"
                                     "brush solid 4\nplane 1 0 0 0\nplane -1 0 0 -10\n"
                                     "plane 0 1 0 1\nplane 0 -1 0 1\n" // empty
                                     "brush solid 4\nplane 0 0 1 0\nplane 0 0 -1 5\n"
                                     "plane 1 0 0 1\nplane -1 0 0 1\n" // unbounded in y
                                     "box solid 0 0 0 1 1 1\n",
                                     "degenerate");
    ASSERT_TRUE(spec.ok()) << spec.error().message();
    const Map map = build_map(spec.value(), "degenerate");
    EXPECT_EQ(map.collision_brushes.size(), 1u);
    EXPECT_EQ(map.stats.degenerate.total(), 2u);
    EXPECT_EQ(map.stats.degenerate.empty + map.stats.degenerate.unbounded, 2u);
}

} // namespace
} // namespace dsoc::maps
