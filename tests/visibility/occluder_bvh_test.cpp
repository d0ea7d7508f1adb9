#include "dsoc/visibility/occluder_bvh.hpp"

#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"
#include "region_test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace dsoc::visibility {
namespace {

TestWorld world_of_kind(int kind) {
    return kind == 0   ? make_walls_world(7, 80, 3000.0f)
           : kind == 1 ? make_city_world(4, 5, 5)
                       : make_corridor_world(7, 4, 4);
}

/// What the tree must offer: every occluder whose bounds clip_segment_to_box() finds
/// the segment touching, by brute force over the world.
std::vector<OccluderId> touching(const OccluderWorld& world, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 d = b - a;
    const glm::vec3 inv(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
    std::vector<OccluderId> ids;
    for (OccluderId id = 0; id < world.size(); ++id) {
        float t0 = 0.0f;
        float t1 = 1.0f;
        if (clip_segment_to_box(a, inv, world.occluder(id).bounds(), t0, t1)) {
            ids.push_back(id);
        }
    }
    return ids;
}

std::vector<OccluderId> offered(const OccluderBvh& bvh, glm::vec3 a, glm::vec3 b) {
    std::vector<OccluderId> ids;
    EXPECT_FALSE(bvh.any_touching_segment(a, b, [&](OccluderId id) {
        ids.push_back(id);
        return false;
    }));
    std::sort(ids.begin(), ids.end());
    return ids;
}

TEST(OccluderBvh, OffersExactlyTheOccludersWhoseBoundsTheSegmentTouches) {
    // Random segments, and the ones a slab test gets wrong most easily: parallel to an
    // axis, starting on an occluder's side and running along it (0 times infinity),
    // of length zero, and crossing the world.
    std::mt19937 rng(71);
    int touched = 0;
    int grazing = 0;
    for (int kind = 0; kind < 3; ++kind) {
        const TestWorld tw = world_of_kind(kind);
        const OccluderBvh bvh(tw.world);
        const Aabb area = tw.world.bounds();
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const auto point = [&] {
            return area.min + (area.max - area.min) * glm::vec3(u(rng), u(rng), u(rng));
        };
        for (int i = 0; i < 3000; ++i) {
            glm::vec3 a = point();
            glm::vec3 b = point();
            const int shape = i % 6;
            if (shape == 1) { // along one axis
                const int keep = static_cast<int>(rng() % 3);
                for (int axis = 0; axis < 3; ++axis) {
                    b[axis] = axis == keep ? b[axis] : a[axis];
                }
            } else if (shape == 2 || shape == 3) { // in the plane of an occluder's side
                const Aabb& o =
                    tw.world.occluder(static_cast<OccluderId>(rng() % tw.world.size())).bounds();
                const int axis = static_cast<int>(rng() % 3);
                a[axis] = b[axis] = (rng() % 2 != 0) ? o.max[axis] : o.min[axis];
                ++grazing;
            } else if (shape == 4) {
                b = a; // a point
            }
            const std::vector<OccluderId> want = touching(tw.world, a, b);
            touched += want.empty() ? 0 : 1;
            ASSERT_EQ(offered(bvh, a, b), want) << "world " << kind << " segment " << i;
        }
    }
    EXPECT_GT(touched, 3000); // the segments do reach occluders
    EXPECT_GT(grazing, 1000);
}

TEST(OccluderBvh, StopsAtTheFirstYesAndOffersEverythingForANonFiniteSegment) {
    const TestWorld tw = make_city_world(3, 4, 4);
    const OccluderBvh bvh(tw.world);
    const Aabb area = tw.world.bounds();
    const glm::vec3 a = area.min;
    const glm::vec3 b = area.max; // the diagonal touches several buildings
    ASSERT_GT(touching(tw.world, a, b).size(), 2u);
    int calls = 0;
    EXPECT_TRUE(bvh.any_touching_segment(a, b, [&](OccluderId) { return ++calls == 2; }));
    EXPECT_EQ(calls, 2);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<OccluderId> all;
    EXPECT_FALSE(bvh.any_touching_segment(a, glm::vec3(nan, b.y, b.z), [&](OccluderId id) {
        all.push_back(id);
        return false;
    }));
    EXPECT_EQ(all.size(), tw.world.size());
    const OccluderBvh empty{OccluderWorld{}};
    EXPECT_FALSE(empty.any_touching_segment(a, b, [](OccluderId) { return true; }));
}

TEST(OccluderBvh, TheShaftStageAnswersAndHintsAsWithoutTheTree) {
    // Pairs moving a few units a step, each carrying its hint from test to test as the
    // manager does, tested by a stage with the tree and by one without: the same answer
    // and the same hint after every test, and the same answer without a hint (where the
    // tree takes long segments, ShaftOcclusion::kMinTreeCells), at portal depths 0 and
    // 2 (whose sub-tests have no hint). Small grid cells, so that most segments are long.
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> step(-8.0f, 8.0f);
    int clear_before = 0;
    int long_unhinted = 0;
    int hidden = 0;
    int tests = 0;
    for (int kind = 0; kind < 3; ++kind) {
        const TestWorld tw = world_of_kind(kind);
        const OccluderGrid grid(tw.world, 32.0f);
        const OccluderBvh bvh(tw.world);
        for (const int depth : {0, 2}) {
            const ShaftOcclusion with(tw.world, grid, true, depth, &bvh);
            const ShaftOcclusion without(tw.world, grid, true, depth);
            ShaftOcclusion::Scratch scratch;
            testing::for_random_region_box_pairs(tw, rng, 300, [&](Aabb region, Aabb box) {
                std::uint32_t hint_with = 0;
                std::uint32_t hint_without = 0;
                for (int t = 0; t < 12; ++t) {
                    const glm::vec3 r(step(rng), step(rng), 0.0f);
                    const glm::vec3 b(step(rng), step(rng), 0.0f);
                    region = Aabb{region.min + r, region.max + r};
                    box = Aabb{box.min + b, box.max + b};
                    clear_before += hint_with == 0 ? 1 : 0;
                    const Visibility a = with.test(region, box, scratch, &hint_with);
                    const Visibility c = without.test(region, box, scratch, &hint_without);
                    ++tests;
                    hidden += a == Visibility::occluded ? 1 : 0;
                    ASSERT_EQ(a, c) << "world " << kind << " depth " << depth;
                    ASSERT_EQ(hint_with, hint_without) << "world " << kind << " depth " << depth;
                    const glm::vec3 span = glm::abs(box.center() - region.center());
                    long_unhinted +=
                        span.x + span.y + span.z > ShaftOcclusion::kMinTreeCells * grid.cell_size()
                            ? 1
                            : 0;
                    ASSERT_EQ(with.test(region, box, scratch), without.test(region, box, scratch))
                        << "world " << kind << " depth " << depth << ", no hint";
                }
            });
        }
    }
    // The tree's check ran (hint 0 before a test, or a long segment without a hint) and
    // the stage hid boxes.
    EXPECT_GT(clear_before, tests / 20) << clear_before << " of " << tests;
    EXPECT_GT(long_unhinted, tests / 4) << long_unhinted << " of " << tests;
    EXPECT_GT(hidden, tests / 10) << hidden << " of " << tests;
}

} // namespace
} // namespace dsoc::visibility
