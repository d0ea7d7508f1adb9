#include "dsoc/visibility/occluder_bvh.hpp"

#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"
#include "region_test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace dsoc::visibility {
namespace {

TestWorld world_of_kind(int kind) {
    return kind == 0   ? make_walls_world(7, 80, 3000.0f)
           : kind == 1 ? make_city_world(4, 5, 5)
                       : make_corridor_world(7, 4, 4);
}

/// What the tree must offer: every occluder whose bounds, grown by `margin`,
/// clip_segment_to_box() finds the segment touching, by brute force over the world.
std::vector<OccluderId> touching(const OccluderWorld& world, glm::vec3 a, glm::vec3 b,
                                 float margin = 0.0f) {
    const glm::vec3 d = b - a;
    const glm::vec3 inv(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
    std::vector<OccluderId> ids;
    for (OccluderId id = 0; id < world.size(); ++id) {
        const Aabb& o = world.occluder(id).bounds();
        const Aabb grown{o.min - glm::vec3(margin), o.max + glm::vec3(margin)};
        float t0 = 0.0f;
        float t1 = 1.0f;
        if (clip_segment_to_box(a, inv, grown, t0, t1)) {
            ids.push_back(id);
        }
    }
    return ids;
}

std::vector<OccluderId> offered(const OccluderBvh& bvh, glm::vec3 a, glm::vec3 b,
                                float margin = 0.0f) {
    std::vector<OccluderId> ids;
    EXPECT_FALSE(bvh.any_touching_segment(
        a, b,
        [&](OccluderId id) {
            ids.push_back(id);
            return false;
        },
        margin));
    std::sort(ids.begin(), ids.end());
    return ids;
}

/// A point of occluder `o`'s bounds: on its side across `axis` (min or max by `high`),
/// at fractions `u`, `v` along the other two axes.
glm::vec3 on_side(const Aabb& o, int axis, bool high, float u, float v) {
    glm::vec3 p = o.min;
    p[(axis + 1) % 3] = o.min[(axis + 1) % 3] + (o.max - o.min)[(axis + 1) % 3] * u;
    p[(axis + 2) % 3] = o.min[(axis + 2) % 3] + (o.max - o.min)[(axis + 2) % 3] * v;
    p[axis] = high ? o.max[axis] : o.min[axis];
    return p;
}

TEST(OccluderBvh, OffersExactlyTheOccludersWhoseBoundsTheSegmentTouches) {
    // Random segments, and the ones a slab test gets wrong most easily: parallel to an
    // axis; in the plane of an occluder's side (0 times infinity); starting on a side
    // and leaving it, or ending on one (entry and exit equal); through a corner; with a
    // direction of -0 or a subnormal on an axis; of length zero; beside a side, within
    // the witnesses' margin of it. Trees split by the surface area heuristic and at
    // medians throughout; each segment asked without a margin and with the witnesses'.
    constexpr float kMargin = ShaftOcclusion::kWitnessMargin;
    std::mt19937 rng(71);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int touched = 0;
    int grazing = 0;
    int within_margin = 0; // segments the margin makes touch an occluder more
    for (int kind = 0; kind < 3; ++kind) {
        const TestWorld tw = world_of_kind(kind);
        const Aabb area = tw.world.bounds();
        const auto point = [&] {
            return area.min + (area.max - area.min) * glm::vec3(u(rng), u(rng), u(rng));
        };
        const auto some_occluder = [&]() -> const Aabb& {
            return tw.world.occluder(static_cast<OccluderId>(rng() % tw.world.size())).bounds();
        };
        for (const int sah_levels : {OccluderBvh::kSahLevels, 0}) {
            const OccluderBvh bvh(tw.world, sah_levels);
            // Below the surface area heuristic's levels, medians: each level a quarter.
            const double quarters =
                std::ceil(std::log2(static_cast<double>(tw.world.size())) / 2.0);
            EXPECT_LE(bvh.depth(), sah_levels + static_cast<int>(quarters))
                << "world " << kind << " sah levels " << sah_levels;
            for (int i = 0; i < 4000; ++i) {
                glm::vec3 a = point();
                glm::vec3 b = point();
                const int shape = i % 10;
                const int axis = static_cast<int>(rng() % 3);
                if (shape == 1) { // along one axis
                    for (int k = 0; k < 3; ++k) {
                        b[k] = k == axis ? b[k] : a[k];
                    }
                } else if (shape == 2 || shape == 3) { // in the plane of an occluder's side
                    const Aabb& o = some_occluder();
                    a[axis] = b[axis] = (rng() % 2 != 0) ? o.max[axis] : o.min[axis];
                    ++grazing;
                } else if (shape == 4) {
                    b = a;               // a point
                } else if (shape == 5) { // from a side, away from the occluder
                    const Aabb& o = some_occluder();
                    const bool high = rng() % 2 != 0;
                    a = on_side(o, axis, high, u(rng), u(rng));
                    b = a;
                    b[axis] += high ? 50.0f : -50.0f;
                    b[(axis + 1) % 3] += 40.0f * (u(rng) - 0.5f);
                    ++grazing;
                } else if (shape == 6) { // ending on a side
                    b = on_side(some_occluder(), axis, rng() % 2 != 0, u(rng), u(rng));
                    ++grazing;
                } else if (shape == 7) { // through or from a corner
                    const Aabb& o = some_occluder();
                    const glm::vec3 c((rng() % 2 != 0) ? o.max.x : o.min.x,
                                      (rng() % 2 != 0) ? o.max.y : o.min.y,
                                      (rng() % 2 != 0) ? o.max.z : o.min.z);
                    a = rng() % 2 != 0 ? c : c + (c - b);
                    ++grazing;
                } else if (shape == 8) { // a direction of -0 or a subnormal on one axis
                    a[axis] = 0.0f;
                    b[axis] = rng() % 2 != 0 ? -0.0f : 1.0e-40f;
                } else if (shape == 9) { // beside a side, outside it by half the margin
                    const Aabb& o = some_occluder();
                    const bool high = rng() % 2 != 0;
                    a[axis] = b[axis] =
                        high ? o.max[axis] + 0.5f * kMargin : o.min[axis] - 0.5f * kMargin;
                }
                const std::vector<OccluderId> want = touching(tw.world, a, b);
                touched += want.empty() ? 0 : 1;
                ASSERT_EQ(offered(bvh, a, b), want)
                    << "world " << kind << " segment " << i << " sah levels " << sah_levels;
                const std::vector<OccluderId> want_near = touching(tw.world, a, b, kMargin);
                within_margin += want_near.size() > want.size() ? 1 : 0;
                ASSERT_EQ(offered(bvh, a, b, kMargin), want_near)
                    << "world " << kind << " segment " << i << " sah levels " << sah_levels
                    << " margin " << kMargin;
            }
        }
    }
    EXPECT_GT(touched, 6000); // the segments do reach occluders
    EXPECT_GT(grazing, 8000);
    EXPECT_GT(within_margin, 500);
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
    // Finite ends whose difference overflows, and an infinite end: every occluder too.
    const float big = std::numeric_limits<float>::max();
    const float inf = std::numeric_limits<float>::infinity();
    for (const auto& [from, to] : {std::pair{glm::vec3(-big, a.y, a.z), glm::vec3(big, b.y, b.z)},
                                   std::pair{a, glm::vec3(b.x, inf, b.z)}}) {
        std::size_t count = 0;
        EXPECT_FALSE(bvh.any_touching_segment(from, to, [&](OccluderId) {
            ++count;
            return false;
        }));
        EXPECT_EQ(count, tw.world.size());
    }
    const OccluderBvh empty{OccluderWorld{}};
    EXPECT_FALSE(empty.any_touching_segment(a, b, [](OccluderId) { return true; }));
    // One occluder: a root holding it alone.
    OccluderWorld one;
    one.add(ConvexPolyhedron::from_aabb(Aabb{glm::vec3(0.0f), glm::vec3(10.0f)}));
    const OccluderBvh single(one);
    EXPECT_EQ(offered(single, glm::vec3(-5.0f, 5.0f, 5.0f), glm::vec3(15.0f, 5.0f, 5.0f)),
              std::vector<OccluderId>{0});
    EXPECT_TRUE(
        offered(single, glm::vec3(-5.0f, 15.0f, 5.0f), glm::vec3(15.0f, 15.0f, 5.0f)).empty());
}

TEST(OccluderBvh, TheShaftStageAnswersAndHintsAsWithoutTheTree) {
    // Pairs moving a few units a step, each carrying its hint from test to test as the
    // manager does, tested by a stage with the tree and by one without: the same answer
    // and the same hint after every test, and the same answer without a hint (where the
    // tree takes long segments, ShaftOcclusion::kMinTreeCells), at portal depths 0 and
    // 2 (whose sub-tests have no hint). Small grid cells, so that most segments are long.
    std::mt19937 rng(17);
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
                    testing::step_pair(rng, 8.0f, region, box);
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

TEST(OccluderBvh, AWitnessKeepsItsMarginWithTheTreeAndWithout) {
    // A wall between a region and a box: the centre segment is blocked, and the witness
    // search's segments (the top corners') run level over the wall's top. Half the
    // margin above it they are no witness; twice the margin above, they are. With the
    // tree, every witness segment is checked against every occluder's grown bounds.
    // Without it, the grid walk: the wall's top is the grid's, so the walk does not see
    // a segment half the margin above it (a witness it should not keep: tightness only,
    // see ShaftOcclusion::segment_clear()); twice the margin above, it agrees.
    constexpr float m = ShaftOcclusion::kWitnessMargin;
    constexpr float top = 100.0f;
    OccluderWorld world;
    world.add(ConvexPolyhedron::from_aabb(Aabb{{-8.0f, -200.0f, 0.0f}, {8.0f, 200.0f, top}}));
    const OccluderGrid grid(world, 32.0f);
    const OccluderBvh bvh(world);
    const ShaftOcclusion with(world, grid, true, 0, &bvh);
    const ShaftOcclusion without(world, grid, true, 0);
    for (const float above : {0.5f * m, 2.0f * m}) {
        const Aabb region{{-300.0f, -20.0f, 40.0f}, {-250.0f, 20.0f, top + above}};
        const Aabb box{{250.0f, -10.0f, 40.0f}, {280.0f, 10.0f, top + above}};
        for (const ShaftOcclusion* stage : {&with, &without}) {
            if (stage == &without && above < m) {
                continue; // the walk's blind spot, above
            }
            ShaftOcclusion::Scratch scratch;
            std::uint32_t hint = 0;
            EXPECT_EQ(stage->test(region, box, scratch, &hint), Visibility::visible);
            const std::uint32_t top_corners = 6u << 3 | 6u; // max y and z, the first tried
            if (above < m) {
                EXPECT_EQ(hint & ~0x3fu, ShaftOcclusion::kWitnessHint | ShaftOcclusion::kNoWitness)
                    << "above " << above << (stage == &with ? ", tree" : ", walk");
            } else {
                EXPECT_EQ(hint, ShaftOcclusion::kWitnessHint | top_corners)
                    << "above " << above << (stage == &with ? ", tree" : ", walk");
            }
        }
    }
}

} // namespace
} // namespace dsoc::visibility
