// The plan renders a small hand-made map, goes through a PNG file and back, and every
// known occluder, entity, TBV and the eye region sit where they should, in their colour.

#include "dsoc/inspect/plan_view.hpp"
#include "dsoc/inspect/png_io.hpp"
#include "through_png.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dsoc::inspect {
namespace {

using visibility::Aabb;
using visibility::ConvexPolyhedron;

Aabb around(float x, float y, float half = 15.0f) {
    return {glm::vec3(x - half, y - half, 0.0f), glm::vec3(x + half, y + half, 56.0f)};
}

struct SmallMap {
    std::vector<ConvexPolyhedron> occluders;
    Aabb bounds;
    ClientView view;

    SmallMap() {
        occluders.push_back(ConvexPolyhedron::from_aabb({{0, 0, -16}, {400, 200, 0}}));   // floor
        occluders.push_back(ConvexPolyhedron::from_aabb({{180, 0, 0}, {220, 200, 100}})); // wall
        occluders.push_back(ConvexPolyhedron::from_aabb({{240, 150, 90}, {260, 190, 100}})); // beam
        for (const auto& o : occluders) {
            bounds.extend(o.bounds());
        }
        view.tick = 7;
        view.eye = {50.0f, 100.0f, 40.0f};
        view.eye_region = {{20.0f, 70.0f, 20.0f}, {80.0f, 130.0f, 60.0f}};
        view.viewer_entity = 0;
        view.viewer_box = around(50.0f, 100.0f);
        view.entities = {
            {1, around(100.0f, 40.0f), EntityState::replicated_visible, {}},
            {2, around(100.0f, 160.0f), EntityState::replicated_lookahead, {}},
            {3, around(150.0f, 40.0f), EntityState::replicated_held, {}},
            {4, around(300.0f, 50.0f), EntityState::hidden_tbv, {{270, 20, 0}, {340, 80, 60}}},
            {5, around(300.0f, 120.0f), EntityState::hidden_expired, {}},
            {6, around(360.0f, 170.0f), EntityState::not_replicated, {}},
        };
    }
};

TEST(PlanView, SmallMapDecodesWithExpectedSizeAndColours) {
    const SmallMap m;
    PlanStyle style;
    style.units_per_pixel = 2.0f;
    style.margin = 8;
    style.cut_above = 60.0f; // the beam's bottom (90) is above: left out
    const Image rendered = render_plan(footprints(m.occluders), m.bounds, m.view, style);
    const Image image = testing::through_png(rendered, "dsoc_inspect_plan_test.png");

    // 400 x 200 world units at 2 units per pixel, plus an 8-pixel margin each side.
    ASSERT_EQ(image.width(), 400 / 2 + 16);
    ASSERT_EQ(image.height(), 200 / 2 + 16);

    const PlanFrame frame(m.bounds, style);
    const auto at = [&](float x, float y) { return image.at(frame.pixel_x(x), frame.pixel_y(y)); };

    EXPECT_EQ(image.at(0, 0), kPalette.background);
    // The wall's top is the map's highest point: the brightest shade.
    EXPECT_EQ(at(200.0f, 100.0f),
              (Rgb{kPalette.high_shade, kPalette.high_shade, kPalette.high_shade}));
    // The floor is grey and darker than the wall.
    const Rgb floor = at(140.0f, 100.0f);
    EXPECT_EQ(floor.r, floor.g);
    EXPECT_EQ(floor.g, floor.b);
    EXPECT_GT(floor.r, kPalette.low_shade - 1);
    EXPECT_LT(floor.r, kPalette.high_shade);
    // The beam is cut away: floor shows through.
    EXPECT_EQ(at(250.0f, 170.0f), floor);

    // Entities 1..6 in the order SmallMap lists them, each in its state's colour.
    const Rgb expected[] = {kPalette.replicated_visible, kPalette.replicated_lookahead,
                            kPalette.replicated_held,    kPalette.hidden_tbv,
                            kPalette.hidden_expired,     kPalette.not_replicated};
    for (std::size_t i = 0; i < m.view.entities.size(); ++i) {
        const EntityView& e = m.view.entities[i];
        const glm::vec3 c = e.box.center();
        EXPECT_EQ(at(c.x, c.y), expected[i]) << "entity " << e.id << " " << to_string(e.state);
    }
    EXPECT_EQ(at(50.0f, 100.0f), kPalette.viewer);
    // The TBV's left side, away from its entity; the eye region's left side, outside the viewer.
    EXPECT_EQ(at(270.0f, 30.0f), kPalette.tbv_outline);
    EXPECT_EQ(at(20.0f, 125.0f), kPalette.eye_region);
}

TEST(PlanView, EveryStateHasItsOwnNonGreyColour) {
    const EntityState states[] = {
        EntityState::replicated_visible, EntityState::replicated_lookahead,
        EntityState::replicated_held,    EntityState::hidden_tbv,
        EntityState::hidden_expired,     EntityState::not_replicated};
    for (const EntityState a : states) {
        const Rgb c = kPalette.of(a);
        EXPECT_FALSE(c.r == c.g && c.g == c.b) << to_string(a) << " would read as an occluder";
        for (const EntityState b : states) {
            if (a != b) {
                EXPECT_NE(c, kPalette.of(b)) << to_string(a) << " vs " << to_string(b);
            }
        }
    }
}

TEST(PlanView, NotSentColoursAreCoolNotAlarmRed) {
    // Hidden is the usual state of most entities: their colours must not read as an
    // error (red), and must be darker than every sent colour.
    for (const EntityState s :
         {EntityState::hidden_tbv, EntityState::hidden_expired, EntityState::not_replicated}) {
        const Rgb c = kPalette.of(s);
        EXPECT_GE(c.b, c.r) << to_string(s);
        for (const EntityState sent :
             {EntityState::replicated_visible, EntityState::replicated_lookahead,
              EntityState::replicated_held}) {
            const Rgb v = kPalette.of(sent);
            if (s != EntityState::hidden_tbv) {
                EXPECT_LT(c.r + c.g + c.b, v.r + v.g + v.b)
                    << to_string(s) << " vs " << to_string(sent);
            }
        }
    }
}

TEST(PlanView, RefusesEmptyBoundsAndOversizedPictures) {
    const ClientView view;
    EXPECT_THROW((void)render_plan({}, Aabb::empty(), view), std::invalid_argument);
    PlanStyle tiny;
    tiny.units_per_pixel = 0.01f;
    EXPECT_THROW((void)render_plan({}, Aabb{{0, 0, 0}, {1000, 1000, 10}}, view, tiny),
                 std::invalid_argument);
}

} // namespace
} // namespace dsoc::inspect
