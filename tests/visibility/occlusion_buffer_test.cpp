#include "dsoc/visibility/seeds/occlusion_buffer.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include "test_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

namespace dsoc::visibility {
namespace {

using testing::cube;
using testing::Scene;

TEST(OcclusionBuffer, WallHidesWhatIsBehindIt) {
    Scene s;
    s.add_box({100, -500, -500}, {110, 500, 500});
    s.build();
    OcclusionBuffer buffer;
    buffer.build(glm::vec3(0.0f), s.world, s.bsp);
    EXPECT_EQ(buffer.test_box(cube({200, 0, 0}, 10)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({200, 100, 50}, 10)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({50, 0, 0}, 10)), Visibility::visible);   // in front
    EXPECT_EQ(buffer.test_box(cube({-200, 0, 0}, 10)), Visibility::visible); // behind the eye
    EXPECT_EQ(buffer.test_box(cube({200, 0, 0}, 95)), Visibility::occluded); // inside the wall
    EXPECT_EQ(buffer.test_box(cube({150, 0, 0}, 55)), Visibility::visible);  // pokes out in front
    EXPECT_EQ(buffer.test_box(cube({1000, 1000, 0}, 10)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({1000, 6000, 0}, 10)), Visibility::visible); // past its edge
    EXPECT_EQ(buffer.test_box(cube({0, 0, 0}, 1)), Visibility::visible);        // contains eye
    EXPECT_EQ(buffer.test_box(Aabb::empty()), Visibility::visible);
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(buffer.test_box({{200, 0, 0}, {inf, 10, 10}}), Visibility::visible);
    EXPECT_EQ(buffer.test_box({{nan, 0, 0}, {210, 10, 10}}), Visibility::visible);
    EXPECT_GT(buffer.stats().texels_written, 0);
}

TEST(OcclusionBuffer, WallAcrossCubeSeamsAndBehindTheEyePlane) {
    // A huge wall at x = 50 seen from the eye: it spans +x and reaches into +-y, +-z.
    Scene s;
    s.add_box({50, -5000, -5000}, {60, 5000, 5000});
    // A wall that crosses the eye's y = 0 plane beside the eye (spans +y, +x and -x).
    s.add_box({-2000, 30, -2000}, {2000, 40, 2000});
    s.build();
    OcclusionBuffer buffer;
    buffer.build(glm::vec3(0.0f), s.world, s.bsp);
    // Diagonal boxes whose projection straddles the +x/+y/+z faces.
    EXPECT_EQ(buffer.test_box(cube({400, 400, 400}, 20)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({400, -400, -400}, 20)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({-400, 400, 0}, 20)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({-400, -400, 0}, 20)), Visibility::visible);
    // A box spanning the gap region between the walls.
    EXPECT_EQ(buffer.test_box(cube({20, 10, 0}, 5)), Visibility::visible);
}

TEST(OcclusionBuffer, EyeInsideAnOccluderWritesNothing) {
    Scene s;
    s.add_box({-10, -10, -10}, {10, 10, 10});
    s.build();
    OcclusionBuffer buffer;
    buffer.build(glm::vec3(0.0f), s.world, s.bsp);
    EXPECT_EQ(buffer.stats().occluders_written, 0);
    EXPECT_EQ(buffer.test_box(cube({100, 0, 0}, 5)), Visibility::visible);
}

TEST(OcclusionBuffer, PyramidLevelsHoldTheMaxOfTheirFourChildren) {
    testing::expect_pyramid_of_maxima<OcclusionBuffer, OcclusionBufferConfig>(
        glm::vec3(700.0f, 800.0f, 60.0f));
}

TEST(OcclusionBuffer, BudgetLimitsOccluders) {
    const Scene s(make_corridor_world(5, 6, 6));
    OcclusionBufferConfig config;
    config.max_occluders = 5;
    OcclusionBuffer buffer(config);
    buffer.build({700.0f, 800.0f, 60.0f}, s.world, s.bsp);
    EXPECT_EQ(buffer.stats().occluders_visited, 5);
    config.max_occluders = 0;
    OcclusionBuffer none(config);
    none.build({700.0f, 800.0f, 60.0f}, s.world, s.bsp);
    EXPECT_EQ(none.stats().occluders_visited, 0);
    EXPECT_EQ(none.test_box(cube({5000, 5000, 60}, 1)), Visibility::visible);
}

TEST(OcclusionBuffer, ValidateNamesTheField) {
    OcclusionBufferConfig config;
    EXPECT_TRUE(validate(config).empty());
    config.face_resolution = 100;
    config.near_distance = 0.0f;
    testing::expect_problems_naming(validate(config), {"face_resolution", "near_distance"});
}

} // namespace
} // namespace dsoc::visibility

namespace dsoc::visibility {
namespace {

TEST(OcclusionBufferRegion, WallHidesFromEveryEyeButAGapSeenFromACornerDoesNot) {
    Scene s;
    // Two wall halves at x = 100 with a gap at y in [-10, 10].
    s.add_box({100, -1000, -1000}, {110, -10, 1000});
    s.add_box({100, 10, -1000}, {110, 1000, 1000});
    s.build();
    OcclusionBuffer point;
    point.build(glm::vec3(0.0f, -60.0f, 0.0f), s.world, s.bsp);
    OcclusionBuffer region;
    const Aabb viewer = Aabb::from_center_half_extents({0.0f, -60.0f, 0.0f}, {20, 50, 20});
    region.build_region(viewer, s.world, s.bsp);
    EXPECT_EQ(region.region().min, viewer.min);
    // Far behind the lower half, out of line with the gap from every eye: hidden.
    EXPECT_EQ(region.test_box(cube({400, -600, 0}, 10)), Visibility::occluded);
    // Behind the gap as seen from the region's far corner (y = -10 .. +10 passes
    // through the gap from eyes near y = -10), not from the centre (y = -60).
    const Aabb behind_gap = cube({300, 30, 0}, 5);
    EXPECT_EQ(point.test_box(behind_gap), Visibility::occluded);
    EXPECT_EQ(region.test_box(behind_gap), Visibility::visible);
    // Boxes touching the region are visible.
    EXPECT_EQ(region.test_box(cube({15, -60, 0}, 6)), Visibility::visible);
}

TEST(OcclusionBufferRegion, OccluderOverlappingTheRegionIsSkipped) {
    Scene s;
    s.add_box({-5, -5, -5}, {5, 5, 5});            // overlaps the region
    s.add_box({100, -500, -500}, {110, 500, 500}); // a wall in front
    s.build();
    OcclusionBuffer region;
    region.build_region(Aabb::from_center_half_extents({0, 0, 0}, glm::vec3(20.0f)), s.world,
                        s.bsp);
    EXPECT_EQ(region.stats().occluders_written, 1);
    EXPECT_EQ(region.test_box(cube({-200, 0, 0}, 5)), Visibility::visible);
    EXPECT_EQ(region.test_box(cube({300, 0, 0}, 5)), Visibility::occluded);
}

} // namespace
} // namespace dsoc::visibility
