#include "dsoc/visibility/seeds/occlusion_beams.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include "test_scene.hpp"

#include <gtest/gtest.h>

namespace dsoc::visibility {
namespace {

using testing::cube;
using testing::Scene;

TEST(OcclusionBeams, WallBeamHidesOnlyWhatIsBehindIt) {
    Scene s;
    s.add_box({100, -500, -500}, {110, 500, 500});
    s.build();
    OcclusionBeams beams;
    beams.build(glm::vec3(0.0f), s.world, s.bsp);
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
    Scene s;
    s.add_box({100, -500, -500}, {110, 0, 500});
    s.add_box({100, 0, -500}, {110, 500, 500});
    s.build();
    OcclusionBeams beams;
    const glm::vec3 eye(0.0f, -1.0f, 3.0f); // not in the plane of a wall's side
    beams.build(eye, s.world, s.bsp);
    EXPECT_EQ(beams.stats().beams, 2);
    EXPECT_EQ(beams.test_box(cube({300, -3, 0}, 20)), Visibility::visible);
    EXPECT_EQ(beams.test_box(cube({300, 200, 0}, 20)), Visibility::occluded);
}

TEST(OcclusionBeams, EyeInsideOrOnAnOccluderMakesNoBeam) {
    Scene s;
    s.add_box({-10, -10, -10}, {10, 10, 10});
    s.add_box({20, -10, -10}, {30, 10, 10});
    s.build();
    OcclusionBeams beams;
    beams.build(glm::vec3(0.0f), s.world, s.bsp);
    EXPECT_EQ(beams.stats().beams, 1);                         // only the second box
    beams.build(glm::vec3(20.0f, 0.0f, 0.0f), s.world, s.bsp); // on a face of the second
    EXPECT_EQ(beams.stats().beams, 1);                         // only the first
}

TEST(OcclusionBeams, BudgetAndNodeCulling) {
    const Scene s(make_corridor_world(8, 6, 6));
    OcclusionBeamsConfig config;
    config.max_beams = 8;
    OcclusionBeams beams(config);
    beams.build({700.0f, 800.0f, 60.0f}, s.world, s.bsp);
    EXPECT_LE(beams.stats().beams, 8);
    EXPECT_GT(beams.stats().beams, 0);
    config.max_beams = 256;
    OcclusionBeams many(config);
    many.build({700.0f, 800.0f, 60.0f}, s.world, s.bsp);
    EXPECT_GT(many.stats().nodes_culled, 0) << "containment spheres inside beams are skipped";
}

} // namespace
} // namespace dsoc::visibility
