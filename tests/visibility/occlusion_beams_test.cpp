#include "dsoc/visibility/occlusion_beams.hpp"
#include "dsoc/visibility/test_worlds.hpp"

#include "test_scene.hpp"

#include <gtest/gtest.h>

namespace dsoc::visibility {
namespace {

using testing::cube;

TEST(OcclusionBeams, WallBeamHidesOnlyWhatIsBehindIt) {
    OccluderWorld world;
    (void)world.add(ConvexPolyhedron::from_aabb({{100, -500, -500}, {110, 500, 500}}));
    BspTree bsp;
    bsp.build(world);
    OcclusionBeams beams;
    beams.build(glm::vec3(0.0f), world, bsp);
    EXPECT_EQ(beams.stats().beams, 1);
    EXPECT_EQ(beams.test_box(cube({300, 0, 0}, 20)), Visibility::occluded);
    EXPECT_EQ(beams.test_sphere({{300, 0, 0}, 20}), Visibility::occluded);
    EXPECT_EQ(beams.test_box(cube({50, 0, 0}, 20)), Visibility::visible);
    EXPECT_EQ(beams.test_box(cube({1000, 6000, 0}, 20)), Visibility::visible);
    EXPECT_EQ(beams.test_box(cube({-300, 0, 0}, 20)), Visibility::visible);
    EXPECT_EQ(beams.test_box(cube({150, 0, 0}, 55)), Visibility::visible);
}

TEST(OcclusionBeams, BeamsDoNotFuse) {
    // Two walls side by side with no gap between them in projection: the box behind
    // the seam is hidden only by both together, which beams cannot prove.
    OccluderWorld world;
    (void)world.add(ConvexPolyhedron::from_aabb({{100, -500, -500}, {110, 0, 500}}));
    (void)world.add(ConvexPolyhedron::from_aabb({{100, 0, -500}, {110, 500, 500}}));
    BspTree bsp;
    bsp.build(world);
    OcclusionBeams beams;
    const glm::vec3 eye(0.0f, -1.0f, 3.0f); // not in the plane of a wall's side
    beams.build(eye, world, bsp);
    EXPECT_EQ(beams.stats().beams, 2);
    EXPECT_EQ(beams.test_box(cube({300, -3, 0}, 20)), Visibility::visible);
    EXPECT_EQ(beams.test_box(cube({300, 200, 0}, 20)), Visibility::occluded);
}

TEST(OcclusionBeams, EyeInsideOrOnAnOccluderMakesNoBeam) {
    OccluderWorld world;
    (void)world.add(ConvexPolyhedron::from_aabb({{-10, -10, -10}, {10, 10, 10}}));
    (void)world.add(ConvexPolyhedron::from_aabb({{20, -10, -10}, {30, 10, 10}}));
    BspTree bsp;
    bsp.build(world);
    OcclusionBeams beams;
    beams.build(glm::vec3(0.0f), world, bsp);
    EXPECT_EQ(beams.stats().beams, 1);                     // only the second box
    beams.build(glm::vec3(20.0f, 0.0f, 0.0f), world, bsp); // on a face of the second
    EXPECT_EQ(beams.stats().beams, 1);                     // only the first
}

TEST(OcclusionBeams, BudgetAndNodeCulling) {
    const TestWorld tw = make_corridor_world(8, 6, 6);
    BspTree bsp;
    bsp.build(tw.world);
    OcclusionBeamsConfig config;
    config.max_beams = 8;
    OcclusionBeams beams(config);
    beams.build({700.0f, 800.0f, 60.0f}, tw.world, bsp);
    EXPECT_LE(beams.stats().beams, 8);
    EXPECT_GT(beams.stats().beams, 0);
    config.max_beams = 256;
    OcclusionBeams many(config);
    many.build({700.0f, 800.0f, 60.0f}, tw.world, bsp);
    EXPECT_GT(many.stats().nodes_culled, 0) << "containment spheres inside beams are skipped";
}

} // namespace
} // namespace dsoc::visibility
