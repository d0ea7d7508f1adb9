#include "dsoc/visibility/occluder_merge.hpp"
#include "dsoc/visibility/occluder_world.hpp"
#include "dsoc/visibility/reference_visibility.hpp"

#include <gtest/gtest.h>

#include <random>

namespace dsoc::visibility {
namespace {

ConvexPolyhedron box(glm::vec3 lo, glm::vec3 hi) {
    return ConvexPolyhedron::from_aabb({lo, hi});
}

TEST(OccluderMerge, WallOfBricksBecomesOneBox) {
    std::vector<ConvexPolyhedron> wall;
    for (int i = 0; i < 10; ++i) { // ten bricks along x, then a second row on top
        wall.push_back(box({64.0f * i, 0, 0}, {64.0f * (i + 1), 16, 64}));
        wall.push_back(box({64.0f * i, 0, 64}, {64.0f * (i + 1), 16, 128}));
    }
    OccluderMergeStats stats;
    const auto merged = merge_box_occluders(wall, &stats);
    ASSERT_EQ(merged.size(), 1u);
    EXPECT_EQ(stats.boxes, 20u);
    EXPECT_EQ(merged[0].bounds().min, glm::vec3(0, 0, 0));
    EXPECT_EQ(merged[0].bounds().max, glm::vec3(640, 16, 128));
}

TEST(OccluderMerge, DifferentCrossSectionsAndGapsStayApart) {
    std::vector<ConvexPolyhedron> in = {
        box({0, 0, 0}, {64, 16, 64}), box({64, 0, 0}, {128, 16, 60}), // shorter: union is not a box
        box({200, 0, 0}, {264, 16, 64}),                              // gap
    };
    EXPECT_EQ(merge_box_occluders(in).size(), 3u);
}

TEST(OccluderMerge, NeverChangesWhatIsVisible) {
    // Random walls of touching bricks: every segment's answer is the same before and
    // after merging.
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> cell(-8, 8);
    std::vector<ConvexPolyhedron> bricks;
    for (int i = 0; i < 120; ++i) {
        const glm::vec3 lo(32.0f * cell(rng), 32.0f * cell(rng), 32.0f * (cell(rng) % 3));
        bricks.push_back(box(lo, lo + glm::vec3(32.0f)));
    }
    const auto merged = merge_box_occluders(bricks);
    EXPECT_LT(merged.size(), bricks.size());
    OccluderWorld before;
    OccluderWorld after;
    for (const auto& b : bricks) {
        before.add(b);
    }
    for (const auto& m : merged) {
        after.add(m);
    }
    ReferenceVisibility ref_before(before);
    ReferenceVisibility ref_after(after);
    std::uniform_real_distribution<float> coord(-300.0f, 300.0f);
    int differences = 0;
    int blocked = 0;
    for (int i = 0; i < 4000; ++i) {
        const glm::vec3 a(coord(rng), coord(rng), coord(rng) * 0.3f);
        const glm::vec3 b(coord(rng), coord(rng), coord(rng) * 0.3f);
        const bool x = ref_before.segment_blocked(a, b);
        differences += x != ref_after.segment_blocked(a, b) ? 1 : 0;
        blocked += x ? 1 : 0;
    }
    EXPECT_EQ(differences, 0);
    EXPECT_GT(blocked, 200); // the test world blocks something
}

} // namespace
} // namespace dsoc::visibility
