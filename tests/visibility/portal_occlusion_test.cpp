// Portal tests in the shaft stage (ShaftOcclusion with portal_depth > 0): a doorway,
// then a wall behind it, against brute-force segments from many eyes.

#include "dsoc/visibility/cut_plane_fusion.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"
#include "region_test_support.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

namespace dsoc::visibility {
namespace {

using testing::add_box;
using testing::seen_from_lattice;

/// A room whose wall across x = 0 has a doorway (|y| < 48, z < 128), and a second wall
/// beyond it (x 150..166, y -160..100) that closes the view through the doorway but not
/// past its own end; floor and ceiling close the rest.
OccluderWorld doorway_then_wall() {
    OccluderWorld world;
    add_box(world, {-8, -500, 0}, {8, -48, 256}); // wall left of the doorway
    add_box(world, {-8, 48, 0}, {8, 500, 256});   // right of it
    add_box(world, {-8, -48, 128}, {8, 48, 256}); // lintel
    add_box(world, {150, -160, 0}, {166, 100, 256});
    add_box(world, {-600, -600, -16}, {600, 600, 0});
    add_box(world, {-600, -600, 256}, {600, 600, 272});
    return world;
}

TEST(PortalOcclusion, ADoorwayThenAWallHidesWhatNoSinglePlaneDoes) {
    const OccluderWorld world = doorway_then_wall();
    const OccluderGrid grid(world, 64.0f);
    const ShaftOcclusion without(world, grid, true, 0);
    const ShaftOcclusion with(world, grid, true, 2);
    ShaftOcclusion::Scratch scratch;
    const Aabb region{{-200, -24, 48}, {-150, 24, 80}};
    // Behind the far wall's end as seen through the doorway, and behind the first wall
    // as seen past the doorway's edge: neither wall alone hides it.
    const Aabb box{{300, 120, 8}, {330, 150, 64}};
    for (OccluderId id = 0; id < world.size(); ++id) {
        EXPECT_FALSE(shaft_blocked_by(region, box, world.solid_planes(id))) << "occluder " << id;
    }
    EXPECT_EQ(without.test(region, box, scratch), Visibility::visible);
    EXPECT_EQ(with.test(region, box, scratch), Visibility::occluded);
    EXPECT_FALSE(seen_from_lattice(ReferenceVisibility(world), region, box, 7));

    // Through the doorway, before the far wall: seen, and the portal tests say so.
    const Aabb through{{80, -15, 8}, {110, 15, 64}};
    EXPECT_TRUE(seen_from_lattice(ReferenceVisibility(world), region, through, 3));
    EXPECT_EQ(with.test(region, through, scratch), Visibility::visible);
    // Past the far wall's end, in line with the doorway: seen as well.
    const Aabb past{{300, 105, 8}, {330, 135, 64}};
    if (seen_from_lattice(ReferenceVisibility(world), region, past, 7)) {
        EXPECT_EQ(with.test(region, past, scratch), Visibility::visible);
    }
}

TEST(PortalOcclusion, APortalProofIsRememberedInTheHint) {
    const OccluderWorld world = doorway_then_wall();
    const OccluderGrid grid(world, 64.0f);
    const ShaftOcclusion shaft(world, grid, true, 2);
    ShaftOcclusion::Scratch scratch;
    const Aabb region{{-200, -24, 48}, {-150, 24, 80}};
    const Aabb box{{300, 120, 8}, {330, 150, 64}};
    std::uint32_t hint = 0;
    ASSERT_EQ(shaft.test(region, box, scratch, &hint), Visibility::occluded);
    EXPECT_NE(hint & ShaftOcclusion::kPortalHint, 0u) << "a portal proof, not one occluder";
    const std::uint32_t first = hint;
    EXPECT_EQ(shaft.test(region, box, scratch, &hint), Visibility::occluded);
    EXPECT_EQ(hint, first) << "the same plane proves it again";
    // A hint naming a plane that does not separate the pair is dropped, and the full
    // test still proves the box hidden.
    hint = ShaftOcclusion::kPortalHint | (2u << 29) | 4u; // the floor's mid-plane, across z
    EXPECT_EQ(shaft.test(region, box, scratch, &hint), Visibility::occluded);
    EXPECT_EQ(hint, first);
    // A visible box clears the hint.
    EXPECT_EQ(shaft.test(region, Aabb{{80, -15, 8}, {110, 15, 64}}, scratch, &hint),
              Visibility::visible);
    EXPECT_EQ(hint, 0u);
}

TEST(PortalOcclusion, AfterFailedPortalTestsTheNextHintedQuerySkipsThem) {
    const OccluderWorld world = doorway_then_wall();
    const OccluderGrid grid(world, 64.0f);
    const ShaftOcclusion shaft(world, grid, true, 2);
    ShaftOcclusion::Scratch scratch;
    const Aabb region{{-200, -24, 48}, {-150, 24, 80}};
    const Aabb hidden{{300, 120, 8}, {330, 150, 64}};
    // Seen through the doorway, off to the side: the centre segment hits the wall
    // beside the doorway, so the portal tests run, and fail.
    const Aabb seen{{90, -120, 8}, {120, -90, 64}};
    ASSERT_TRUE(seen_from_lattice(ReferenceVisibility(world), region, seen, 3));
    std::uint32_t hint = 0;
    ASSERT_EQ(shaft.test(region, seen, scratch, &hint), Visibility::visible);
    ASSERT_NE(hint, 0u) << "a failed portal test is remembered";
    // The next hinted query skips the portal tests ("visible" is always allowed)...
    EXPECT_EQ(shaft.test(region, hidden, scratch, &hint), Visibility::visible);
    // ...and the one after runs them again.
    EXPECT_EQ(shaft.test(region, hidden, scratch, &hint), Visibility::occluded);
    // Without a hint nothing is skipped.
    EXPECT_EQ(shaft.test(region, hidden, scratch), Visibility::occluded);
}

TEST(PortalOcclusion, UncoveredPiecesHoldEveryOpenCrossing) {
    // coverage(): every point of S outside every cut occluder lies in some piece.
    const OccluderWorld world = doorway_then_wall();
    const OccluderGrid grid(world, 64.0f);
    const CutPlaneFusion fusion(world, grid);
    OccluderGrid::Scratch grid_scratch;
    CutPlaneFusion::Scratch scratch;
    const Aabb region{{-200, -60, 48}, {-150, 60, 80}};
    const Aabb box{{300, -100, 8}, {330, 200, 64}};
    const CutPlane plane{0, 0.0f}; // through the doorway wall
    ASSERT_EQ(fusion.coverage(region, box, plane, grid_scratch, scratch, false),
              CutPlaneFusion::Coverage::partial);
    ASSERT_FALSE(scratch.pieces.empty());
    glm::dvec2 lo;
    glm::dvec2 hi;
    ASSERT_TRUE(CutPlaneFusion::crossing_rectangle(region, box, plane, lo, hi));
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> t01(0.0, 1.0);
    int open = 0;
    for (int i = 0; i < 20000; ++i) {
        const glm::dvec2 p = lo + (hi - lo) * glm::dvec2(t01(rng), t01(rng));
        const glm::vec3 point(0.0f, static_cast<float>(p.x), static_cast<float>(p.y));
        bool solid = false;
        for (OccluderId id = 0; id < world.size() && !solid; ++id) {
            solid = world.occluder(id).bounds().contains(point) &&
                    world.occluder(id).bounds().min.x < 0.0f;
        }
        if (solid) {
            continue;
        }
        ++open;
        bool in_piece = false;
        for (const auto& piece : scratch.pieces) {
            glm::dvec2 plo;
            glm::dvec2 phi;
            CutPlaneFusion::bounds(piece, plo, phi);
            in_piece = in_piece || (p.x >= plo.x - 1e-6 && p.x <= phi.x + 1e-6 &&
                                    p.y >= plo.y - 1e-6 && p.y <= phi.y + 1e-6);
        }
        EXPECT_TRUE(in_piece) << "open point (" << p.x << ", " << p.y << ") in no piece";
    }
    EXPECT_GT(open, 1000) << "the doorway is part of S";
}

TEST(PortalOcclusion, RandomRegionsNeverHideWhatAnEyeSeesAndPortalsCullMore) {
    std::mt19937 rng(23);
    int configurations = 0;
    int culled_fused = 0;
    int culled_portals = 0;
    int misses = 0;
    for (int w = 0; w < 3; ++w) {
        const TestWorld tw = w == 0   ? testing::fragmented_corridor_world(7)
                             : w == 1 ? make_corridor_world(13, 4, 4)
                                      : make_city_world(5, 4, 4);
        const OccluderGrid grid(tw.world);
        const ShaftOcclusion fused(tw.world, grid, true, 0);
        const ShaftOcclusion portals(tw.world, grid, true, 2);
        ShaftOcclusion::Scratch scratch;
        const ReferenceVisibility ref(tw.world);
        testing::for_random_region_box_pairs(
            tw, rng, 600, [&](const Aabb& region, const Aabb& box) {
                ++configurations;
                const bool fused_hides = fused.test(region, box, scratch) == Visibility::occluded;
                // A random (stale or meaningless) hint changes the work, never the guarantee.
                std::uint32_t hint = rng() % 2 == 0 ? static_cast<std::uint32_t>(rng())
                                                    : static_cast<std::uint32_t>(rng() % 64);
                const bool portals_hide =
                    portals.test(region, box, scratch, &hint) == Visibility::occluded;
                EXPECT_TRUE(portals_hide || !fused_hides) << "portals only add proofs";
                culled_fused += fused_hides ? 1 : 0;
                if (!portals_hide) {
                    return;
                }
                ++culled_portals;
                misses += seen_from_lattice(ref, region, box) ? 1 : 0;
            });
    }
    EXPECT_EQ(misses, 0) << "of " << culled_portals << " culled";
    EXPECT_GT(culled_portals, culled_fused + configurations / 100)
        << culled_portals << " vs " << culled_fused << " of " << configurations;
    std::printf("portals: %d configurations, fusion %d culled, portals %d culled, %d misses\n",
                configurations, culled_fused, culled_portals, misses);
}

} // namespace
} // namespace dsoc::visibility
