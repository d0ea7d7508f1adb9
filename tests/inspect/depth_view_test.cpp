// The z-pyramid dump: a wall in front of the eye shows on the +x face at its depth,
// the open -x face shows "nothing known", and the strip has six faces.

#include "dsoc/inspect/depth_view.hpp"
#include "dsoc/inspect/png_io.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"
#include "through_png.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dsoc::inspect {
namespace {

using visibility::Aabb;

TEST(DepthView, WallInFrontOfTheEyeShowsOnThePlusXFace) {
    std::vector<visibility::ConvexPolyhedron> occluders{
        visibility::ConvexPolyhedron::from_aabb({{100, -5000, -5000}, {200, 5000, 5000}})};
    const auto scene = visibility::OccluderScene::build(occluders);
    visibility::OcclusionBuffer buffer({64});
    buffer.build(glm::vec3(0.0f), scene->world, scene->bsp);
    const DepthPyramid pyramid = DepthPyramid::of(buffer);
    ASSERT_EQ(pyramid.resolution, 64);

    DepthStyle style;
    style.far_depth = 1000.0f;
    style.face_pixels = 128;
    style.gap = 4;
    const int level = 1; // 32 x 32 texels, scaled by 4
    const Image face = render_depth_face(pyramid, 0, level, style);
    ASSERT_EQ(face.width(), 128);
    ASSERT_EQ(face.height(), 128);
    // The wall's near face is 100 units ahead along +x: every +x texel is at a depth
    // of about 100 (the buffer may round up, never below 100).
    const float centre = buffer.depth(0, level, 16, 16);
    EXPECT_GE(centre, 100.0f);
    EXPECT_LT(centre, 120.0f);
    EXPECT_EQ(face.at(64, 64), depth_colour(centre, style));
    const Rgb c = face.at(64, 64);
    EXPECT_EQ(c.r, c.g);
    EXPECT_GT(c.r, 255 * 0.85); // near: bright

    const Image strip = testing::through_png(render_depth_strip(pyramid, level, style),
                                             "dsoc_inspect_depth_test.png");
    ASSERT_EQ(strip.width(), 6 * 128 + 7 * 4);
    ASSERT_EQ(strip.height(), 128 + 2 * 4);
    EXPECT_EQ(strip.at(4 + 64, 4 + 64), c);                   // +x: the wall
    EXPECT_EQ(strip.at(4 + 132 + 64, 4 + 64), kUnknownDepth); // -x: open
    EXPECT_EQ(strip.at(0, 0), (Rgb{0, 0, 0}));                // gap
}

TEST(DepthView, LabeledStripNamesEachFaceAboveItAndKeepsTheFaces) {
    visibility::OcclusionBuffer buffer({16});
    buffer.begin(glm::vec3(0.0f));
    buffer.finish();
    const DepthPyramid pyramid = DepthPyramid::of(buffer);
    DepthStyle style;
    style.face_pixels = 64;
    style.gap = 4;
    const Image strip = render_depth_strip(pyramid, 0, style);
    const Image labeled = render_labeled_depth_strip(pyramid, 0, style);
    ASSERT_EQ(labeled.width(), strip.width());
    const int band = labeled.height() - strip.height();
    ASSERT_GT(band, 0);
    EXPECT_EQ(Image::cropped(labeled, 0, band, strip.width(), strip.height()).pixels(),
              strip.pixels());
    const Rgb text = CaptionStyle{}.text;
    for (int f = 0; f < 6; ++f) {
        int lit = 0;
        for (int y = 0; y < band; ++y) {
            for (int x = 4 + f * 68; x < 4 + f * 68 + 64; ++x) {
                lit += labeled.at(x, y) == text ? 1 : 0;
            }
        }
        EXPECT_GT(lit, 10) << kFaceLabels[f];
    }
    // The legend names the far depth of the style.
    style.far_depth = 512.0f;
    EXPECT_NE(depth_legend(style).front().label.find("512"), std::string::npos);
    EXPECT_EQ(depth_legend(style).back().colour, kUnknownDepth);
}

TEST(DepthView, RejectsFacesAndLevelsOutOfRange) {
    visibility::OcclusionBuffer buffer({16});
    buffer.begin(glm::vec3(0.0f));
    buffer.finish();
    const DepthPyramid pyramid = DepthPyramid::of(buffer);
    EXPECT_THROW((void)render_depth_face(pyramid, 6, 0), std::invalid_argument);
    EXPECT_THROW((void)render_depth_face(pyramid, 0, pyramid.levels), std::invalid_argument);
    EXPECT_EQ(render_depth_face(pyramid, 5, 0).at(0, 0), kUnknownDepth);
}

} // namespace
} // namespace dsoc::inspect
