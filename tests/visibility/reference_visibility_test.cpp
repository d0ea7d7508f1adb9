#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace dsoc::visibility {
namespace {

const std::vector<Plane> kUnitBox = {{{1, 0, 0}, 1},  {{-1, 0, 0}, 1}, {{0, 1, 0}, 1},
                                     {{0, -1, 0}, 1}, {{0, 0, 1}, 1},  {{0, 0, -1}, 1}};

TEST(ReferenceVisibility, SegmentThroughTheInteriorIsBlocked) {
    EXPECT_TRUE(segment_blocked_by({-5, 0, 0}, {5, 0, 0}, kUnitBox));
    EXPECT_TRUE(segment_blocked_by({-5, 0.5f, 0.5f}, {0, 0, 0}, kUnitBox)); // ends inside
    EXPECT_FALSE(segment_blocked_by({-5, 0, 0}, {-2, 0, 0}, kUnitBox));     // stops short
    EXPECT_FALSE(segment_blocked_by({-5, 3, 0}, {5, 3, 0}, kUnitBox));      // misses
}

TEST(ReferenceVisibility, TouchingIsNotBlocking) {
    EXPECT_FALSE(segment_blocked_by({-5, 1, 0}, {5, 1, 0}, kUnitBox));  // along a face
    EXPECT_FALSE(segment_blocked_by({-5, 1, 1}, {5, 1, 1}, kUnitBox));  // along an edge
    EXPECT_FALSE(segment_blocked_by({-3, -1, 1}, {1, 3, 1}, kUnitBox)); // touches a vertex
    EXPECT_FALSE(segment_blocked_by({-5, 0, 0}, {-1, 0, 0}, kUnitBox)); // ends on a face
}

TEST(ReferenceVisibility, BoxSamplesAndAnswers) {
    std::vector<glm::vec3> samples;
    ReferenceVisibility::box_samples({{0, 0, 0}, {1, 1, 1}}, 3, samples);
    EXPECT_EQ(samples.size(), 1u + 6u * 9u);
    OccluderWorld world;
    (void)world.add(ConvexPolyhedron::from_aabb({{10, -100, -100}, {12, 100, 100}}));
    const ReferenceVisibility reference(world);
    const glm::vec3 eye(0.0f);
    EXPECT_EQ(reference.test_box(eye, {{20, -5, -5}, {30, 5, 5}}), Visibility::occluded);
    EXPECT_EQ(reference.test_box(eye, {{20, 150, -5}, {30, 300, 5}}), Visibility::visible);
    EXPECT_EQ(reference.test_box(eye, {{5, -5, -5}, {30, 5, 5}}), Visibility::visible);
    EXPECT_EQ(reference.test_box(eye, {{-1, -1, -1}, {1, 1, 1}}), Visibility::visible);
    EXPECT_TRUE(reference.segment_blocked(eye, {20, 0, 0}));
    EXPECT_FALSE(reference.segment_blocked(eye, {9, 0, 0}));
}

TEST(TestWorlds, GeneratorsMakeValidWorldsOfTheStatedSize) {
    const TestWorld corridor = make_corridor_world(1, 10, 10);
    EXPECT_GT(corridor.world.size(), 800u);
    EXPECT_LT(corridor.world.size(), 1100u);
    const TestWorld city = make_city_world(2, 5, 5);
    EXPECT_GE(city.world.size(), 25u);
    const TestWorld random = make_random_world(3, 200, 2000.0f);
    EXPECT_GE(random.world.size(), 190u); // a cut brush may rarely come out empty
    const TestWorld walls = make_walls_world(4, 50, 2000.0f);
    EXPECT_EQ(walls.world.size(), 50u);
    for (const TestWorld* tw : {&corridor, &city, &random, &walls}) {
        EXPECT_FALSE(tw->play_area.is_empty());
        for (OccluderId id = 0; id < tw->world.size(); ++id) {
            EXPECT_FALSE(tw->world.occluder(id).is_empty());
            EXPECT_TRUE(tw->world.is_closed(id));
            EXPECT_GE(tw->world.face_planes(id).size(), 4u);
        }
    }
    // Same seed, same world.
    const TestWorld again = make_corridor_world(1, 10, 10);
    ASSERT_EQ(again.world.size(), corridor.world.size());
    EXPECT_EQ(again.world.occluder(500).bounds().min, corridor.world.occluder(500).bounds().min);
}

TEST(Geometry, SpheresDistancesAndFrustum) {
    const Sphere a{{0, 0, 0}, 1};
    const Sphere b{{4, 0, 0}, 1};
    const Sphere m = enclosing_sphere(a, b);
    EXPECT_NEAR(m.radius, 3.0f, 1e-4f);
    EXPECT_NEAR(m.center.x, 2.0f, 1e-4f);
    EXPECT_EQ(enclosing_sphere(Sphere{{0, 0, 0}, 10}, b).radius, 10.0f);
    const Aabb box{{1, 1, 1}, {2, 2, 2}};
    EXPECT_FLOAT_EQ(distance_squared(box, {0, 0, 0}), 3.0f);
    EXPECT_FLOAT_EQ(distance_squared(box, {1.5f, 1.5f, 1.5f}), 0.0f);
    EXPECT_FLOAT_EQ(max_distance_squared(box, {0, 0, 0}), 12.0f);
    const Frustum f =
        Frustum::perspective({0, 0, 0}, {1, 0, 0}, {0, 0, 1}, 1.5708f, 1.0f, 1.0f, 100.0f);
    EXPECT_TRUE(f.may_overlap(Aabb{{10, -1, -1}, {12, 1, 1}}));
    EXPECT_FALSE(f.may_overlap(Aabb{{-12, -1, -1}, {-10, 1, 1}})); // behind
    EXPECT_FALSE(f.may_overlap(Aabb{{10, 20, -1}, {12, 22, 1}}));  // outside 45 degrees
    EXPECT_FALSE(f.may_overlap(Aabb{{200, -1, -1}, {202, 1, 1}})); // beyond far
    EXPECT_TRUE(f.may_overlap(Sphere{{10, 10.5f, 0}, 1.0f}));
}

} // namespace
} // namespace dsoc::visibility
