// Occluder fusion across cut planes, against brute-force segments from many eyes.

#include "dsoc/visibility/cut_plane_fusion.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"
#include "region_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace dsoc::visibility {
namespace {

using testing::add_box;
using testing::fragmented_corridor_world;
using testing::seen_from_lattice;

/// A wall across x = 0 made of two brushes meeting at y = 7, of different thickness,
/// with an eye region in front of it and a box behind it that neither brush hides alone.
struct TwoBrushWall {
    OccluderWorld world;
    Aabb region{{-200, -40, 0}, {-120, 40, 60}};
    Aabb box{{150, -20, 0}, {180, 20, 56}};
    TwoBrushWall() {
        add_box(world, {-8, -600, -100}, {8, 7, 300});
        add_box(world, {-4, 7, -100}, {12, 600, 300});
    }
};

TEST(CutPlaneFusion, AWallOfTwoBrushesHidesWhatNeitherHidesAlone) {
    const TwoBrushWall wall;
    const OccluderWorld& world = wall.world;
    const OccluderGrid grid(world, 128.0f);
    const Aabb& region = wall.region;
    const Aabb& box = wall.box;

    const ShaftOcclusion single(world, grid, false);
    const ShaftOcclusion fused(world, grid, true);
    ShaftOcclusion::Scratch scratch;
    EXPECT_EQ(single.test(region, box, scratch), Visibility::visible); // the seam
    EXPECT_EQ(fused.test(region, box, scratch), Visibility::occluded);
    EXPECT_FALSE(seen_from_lattice(ReferenceVisibility(world), region, box));
}

TEST(CutPlaneFusion, AFusionProofIsRememberedInTheHintAndTriedFirst) {
    // No single brush hides the box, their plane does.
    const TwoBrushWall wall;
    const OccluderGrid grid(wall.world, 128.0f);
    const Aabb& region = wall.region;
    const Aabb& box = wall.box;
    const ShaftOcclusion fused(wall.world, grid, true, 0);
    ShaftOcclusion::Scratch scratch;
    std::uint32_t hint = 0;
    ASSERT_EQ(fused.test(region, box, scratch, &hint), Visibility::occluded);
    ASSERT_NE(hint & ShaftOcclusion::kPortalHint, 0u) << "a plane, not one occluder: " << hint;
    EXPECT_EQ((hint >> 29) & 3u, 0u) << "the plane across x";
    const std::uint32_t first = hint;
    // The box moves along the wall: the hinted plane proves it again.
    EXPECT_EQ(fused.test(region, Aabb{{150, 30, 0}, {180, 70, 56}}, scratch, &hint),
              Visibility::occluded);
    EXPECT_EQ(hint, first);
    // Past the wall's end the plane no longer covers it: the full test answers, and the
    // hint no longer names the plane.
    EXPECT_EQ(fused.test(region, Aabb{{150, 2000, 0}, {180, 2040, 56}}, scratch, &hint),
              Visibility::visible);
    EXPECT_EQ(hint, 0u);
}

TEST(CutPlaneFusion, ADoorwayIsNotCovered) {
    // A wall across x = 0 with a doorway |y| < 48, z < 128: left, right and a lintel.
    OccluderWorld world;
    add_box(world, {-8, -600, 0}, {8, -48, 256});
    add_box(world, {-8, 48, 0}, {8, 600, 256});
    add_box(world, {-8, -48, 128}, {8, 48, 256});
    const OccluderGrid grid(world, 128.0f);
    const ShaftOcclusion fused(world, grid, true);
    ShaftOcclusion::Scratch scratch;
    const ReferenceVisibility ref(world);
    const Aabb region{{-200, -40, 20}, {-120, 40, 80}};

    // Straight through the door: seen.
    const Aabb through{{150, -15, 20}, {180, 15, 76}};
    EXPECT_EQ(fused.test(region, through, scratch), Visibility::visible);
    EXPECT_TRUE(seen_from_lattice(ref, region, through));
    // Far to the side behind the left part and the lintel's end: hidden by the left
    // brush and the lintel together.
    const Aabb aside{{150, -400, 20}, {180, -360, 76}};
    EXPECT_EQ(fused.test(region, aside, scratch), Visibility::occluded);
    EXPECT_FALSE(seen_from_lattice(ref, region, aside));
}

TEST(CutPlaneFusion, TheCrossingRectangleHoldsEveryCrossing) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> pos(-500.0f, 500.0f);
    std::uniform_real_distribution<float> size(1.0f, 120.0f);
    std::uniform_real_distribution<float> t01(0.0f, 1.0f);
    int checked = 0;
    for (int i = 0; i < 2000; ++i) {
        const glm::vec3 rc(pos(rng), pos(rng), pos(rng));
        const glm::vec3 bc(pos(rng), pos(rng), pos(rng));
        const Aabb region{rc, rc + glm::vec3(size(rng), size(rng), size(rng))};
        const Aabb box{bc, bc + glm::vec3(size(rng), size(rng), size(rng))};
        const int axis = static_cast<int>(rng() % 3);
        const CutPlane plane{axis, pos(rng)};
        glm::dvec2 lo;
        glm::dvec2 hi;
        if (!CutPlaneFusion::crossing_rectangle(region, box, plane, lo, hi)) {
            continue;
        }
        const int u = (axis + 1) % 3;
        const int v = (axis + 2) % 3;
        for (int k = 0; k < 50; ++k) {
            const glm::dvec3 r =
                glm::dvec3(region.min) +
                glm::dvec3(region.size()) * glm::dvec3(t01(rng), t01(rng), t01(rng));
            const glm::dvec3 b = glm::dvec3(box.min) +
                                 glm::dvec3(box.size()) * glm::dvec3(t01(rng), t01(rng), t01(rng));
            const double t = (double{plane.offset} - r[axis]) / (b[axis] - r[axis]);
            ASSERT_GT(t, 0.0);
            ASSERT_LT(t, 1.0);
            const glm::dvec3 q = r + (b - r) * t;
            EXPECT_GE(q[u], lo.x - 1e-6);
            EXPECT_LE(q[u], hi.x + 1e-6);
            EXPECT_GE(q[v], lo.y - 1e-6);
            EXPECT_LE(q[v], hi.y + 1e-6);
            ++checked;
        }
    }
    EXPECT_GT(checked, 10000);
}

/// The noise rule written plainly: twice the area over the summed edge lengths.
bool negligible_plainly(const CutPlaneFusion::Polygon& poly) {
    if (poly.n < 3) {
        return true;
    }
    double area2 = 0.0;
    double perimeter = 0.0;
    for (int i = 0; i < poly.n; ++i) {
        const glm::dvec2& p = poly.v[static_cast<std::size_t>(i)];
        const glm::dvec2& q = poly.v[static_cast<std::size_t>((i + 1) % poly.n)];
        area2 += p.x * q.y - q.x * p.y;
        perimeter += glm::length(q - p);
    }
    return perimeter <= 0.0 || std::abs(area2) / perimeter < CutPlaneFusion::kNoiseWidth;
}

TEST(CutPlaneFusion, TheNoiseRuleAnswersAsTheEdgeLengthsDo) {
    // Slivers whose width lies within a few ulps of kNoiseWidth either way, thin and wide
    // rectangles, tilted ones, triangles and degenerate polygons, far from the origin too:
    // the bounds-first rule must give the plain rule's answer every time.
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> pos(-5000.0, 5000.0);
    std::uniform_real_distribution<double> length(0.0, 400.0);
    std::uniform_real_distribution<double> turn(0.0, 6.283185307179586);
    std::uniform_real_distribution<double> near_one(1.0 - 1e-12, 1.0 + 1e-12);
    int negligible = 0;
    int kept = 0;
    for (int i = 0; i < 200000; ++i) {
        CutPlaneFusion::Polygon poly;
        const glm::dvec2 o(pos(rng), pos(rng));
        const int shape = static_cast<int>(rng() % 4);
        if (shape < 3) {
            // A rectangle of length l and width w, axis-aligned or tilted; shapes 0 and 1
            // have the rule's width l w / (l + w) within a few ulps of kNoiseWidth.
            const double l = length(rng);
            double w = CutPlaneFusion::kNoiseWidth;
            if (shape < 2 && l > 2.0 * w) {
                w = w * l / (l - w) * near_one(rng);
            } else if (shape == 2) {
                w *= std::exp2(static_cast<double>(static_cast<int>(rng() % 20)) - 10.0);
            }
            const double a = rng() % 2 == 0 ? 0.0 : turn(rng);
            const glm::dvec2 along(std::cos(a), std::sin(a));
            const glm::dvec2 across(-along.y, along.x);
            poly.n = 4;
            poly.v[0] = o;
            poly.v[1] = o + along * l;
            poly.v[2] = o + along * l + across * w;
            poly.v[3] = o + across * w;
        } else {
            poly.n = static_cast<int>(rng() % 6); // 0 to 5 points, possibly all one
            for (int k = 0; k < poly.n; ++k) {
                poly.v[static_cast<std::size_t>(k)] =
                    rng() % 3 == 0 ? o : o + glm::dvec2(length(rng), length(rng)) * 1e-3;
            }
        }
        const bool plain = negligible_plainly(poly);
        ASSERT_EQ(CutPlaneFusion::negligible(poly), plain) << "polygon " << i;
        (plain ? negligible : kept) += 1;
    }
    EXPECT_GT(negligible, 20000); // both answers are well represented
    EXPECT_GT(kept, 20000);
}

TEST(CutPlaneFusion, RandomRegionsNeverHideWhatAnEyeSeesAndFusionCullsMore) {
    std::mt19937 rng(17);
    int configurations = 0;
    int culled_single = 0;
    int culled_fused = 0;
    int misses = 0;
    for (int w = 0; w < 3; ++w) {
        const TestWorld tw = w == 0   ? fragmented_corridor_world(5)
                             : w == 1 ? make_corridor_world(9, 4, 4)
                                      : make_city_world(3, 4, 4);
        const OccluderGrid grid(tw.world);
        const ShaftOcclusion single(tw.world, grid, false);
        const ShaftOcclusion fused(tw.world, grid, true, 0); // fusion alone, no portals
        ShaftOcclusion::Scratch scratch;
        const ReferenceVisibility ref(tw.world);
        testing::for_random_region_box_pairs(
            tw, rng, 600, [&](const Aabb& region, const Aabb& box) {
                ++configurations;
                const bool single_hides = single.test(region, box, scratch) == Visibility::occluded;
                const bool fused_hides = fused.test(region, box, scratch) == Visibility::occluded;
                EXPECT_TRUE(fused_hides || !single_hides) << "fusion only adds proofs";
                culled_single += single_hides ? 1 : 0;
                if (!fused_hides) {
                    return;
                }
                ++culled_fused;
                misses += seen_from_lattice(ref, region, box) ? 1 : 0;
            });
    }
    EXPECT_EQ(misses, 0) << "of " << culled_fused << " culled";
    // Fusion must prove clearly more than single occluders do (the fragmented world
    // alone makes the difference large).
    EXPECT_GT(culled_fused, culled_single + configurations / 50)
        << culled_fused << " vs " << culled_single << " of " << configurations;
    std::printf("fusion: %d configurations, single %d culled, fused %d culled, %d misses\n",
                configurations, culled_single, culled_fused, misses);
}

} // namespace
} // namespace dsoc::visibility
