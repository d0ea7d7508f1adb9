// The exact single-occluder shaft test against brute-force segments from many eyes.

#include "dsoc/visibility/occluder_region_visibility.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"
#include "region_test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

namespace dsoc::visibility {
namespace {

std::vector<Plane> wall_planes(glm::vec3 lo, glm::vec3 hi) {
    return ConvexPolyhedron::from_aabb({lo, hi}).planes();
}

TEST(ShaftOcclusion, WallBetweenRegionAndBoxBlocksEverySegment) {
    const auto wall = wall_planes({-8, -500, -500}, {8, 500, 500});
    const Aabb region{{-100, -40, -40}, {-50, 40, 40}};
    EXPECT_TRUE(shaft_blocked_by(region, Aabb{{50, -20, -20}, {80, 20, 20}}, wall));
    // A box beside the wall's end is seen from the region.
    EXPECT_FALSE(shaft_blocked_by(region, Aabb{{50, 2000, -20}, {80, 2040, 20}}, wall));
}

TEST(ShaftOcclusion, APillarHidesFromTheCentreButNotFromACorner) {
    // A narrow pillar: the centre of the region is behind it, the region's corners
    // look past it.
    const auto pillar = wall_planes({-8, -10, -500}, {8, 10, 500});
    const Aabb box{{200, -5, -5}, {210, 5, 5}};
    EXPECT_TRUE(shaft_blocked_by(Aabb{{-100, -1, -1}, {-99, 1, 1}}, box, pillar));
    EXPECT_FALSE(shaft_blocked_by(Aabb{{-100, -30, -1}, {-90, 30, 1}}, box, pillar));
}

TEST(OccluderGrid, SegmentQueryFindsEveryOccluderTheSegmentCrosses) {
    // The DDA walk against brute force over every occluder: missing one would only make
    // the shaft test prove less, but it must not happen for segments inside the grid.
    std::mt19937 rng(5);
    int crossings = 0;
    for (int w = 0; w < 2; ++w) {
        const TestWorld tw = w == 0 ? make_walls_world(7, 80, 3000.0f) : make_city_world(4, 5, 5);
        for (const float cell : {64.0f, 256.0f}) {
            OccluderGrid grid(tw.world, cell);
            OccluderGrid::Scratch scratch;
            std::uniform_real_distribution<float> ux(tw.play_area.min.x, tw.play_area.max.x);
            std::uniform_real_distribution<float> uy(tw.play_area.min.y, tw.play_area.max.y);
            std::uniform_real_distribution<float> uz(tw.play_area.min.z, tw.play_area.max.z);
            for (int i = 0; i < 400; ++i) {
                glm::vec3 a(ux(rng), uy(rng), uz(rng));
                glm::vec3 b(ux(rng), uy(rng), uz(rng));
                if (i % 10 == 0) {
                    b.x = a.x; // axis-parallel segments walk a single row of cells
                    b.y = a.y;
                }
                grid.query_segment(a, b, scratch);
                for (OccluderId id = 0; id < tw.world.size(); ++id) {
                    if (!segment_blocked_by(a, b, tw.world.solid_planes(id))) {
                        continue;
                    }
                    ++crossings;
                    EXPECT_NE(std::find(scratch.found.begin(), scratch.found.end(), id),
                              scratch.found.end())
                        << "occluder " << id << " crossed but not found, cell " << cell;
                }
            }
        }
    }
    EXPECT_GT(crossings, 500); // the segments do cross walls
}

TEST(ShaftOcclusion, TheBoxFastPathNeverClaimsMoreThanThePlanes) {
    // The float box path against the double-precision plane test, on random boxes and
    // segments, including ones grazing faces and edges.
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> pos(-4000.0f, 4000.0f);
    std::uniform_real_distribution<float> size(1.0f, 300.0f);
    std::uniform_real_distribution<float> t01(0.0f, 1.0f);
    int through = 0;
    int agreed = 0;
    for (int i = 0; i < 20000; ++i) {
        const glm::vec3 lo(pos(rng), pos(rng), pos(rng));
        const Aabb solid{lo, lo + glm::vec3(size(rng), size(rng), size(rng))};
        const auto planes = ConvexPolyhedron::from_aabb(solid).planes();
        auto point = [&](bool on_face) {
            glm::vec3 p =
                solid.min - glm::vec3(200.0f) +
                (solid.size() + glm::vec3(400.0f)) * glm::vec3(t01(rng), t01(rng), t01(rng));
            if (on_face) { // snap one coordinate onto a face plane: grazing segments
                const int a = static_cast<int>(rng() % 3);
                p[a] = rng() % 2 == 0 ? solid.min[a] : solid.max[a];
            }
            return p;
        };
        const glm::vec3 a = point(i % 3 == 0);
        const glm::vec3 b = point(i % 5 == 0);
        const bool fast = segment_through_box(a, b, solid);
        const bool exact = segment_blocked_by(a, b, planes);
        if (fast) {
            ++through;
            EXPECT_TRUE(exact) << "box path claims a block the planes do not";
        }
        agreed += fast == exact ? 1 : 0;
    }
    EXPECT_GT(through, 2000);
    EXPECT_GT(agreed, 19900); // it differs only within the 1/64-unit shrink
}

/// The corner argument itself, the slow twin of shaft_blocked_by_box(): each of the 64
/// segments between a corner of `region` and a corner of `box` through `solid`.
bool every_corner_segment_through(const Aabb& region, const Aabb& box, const Aabb& solid) {
    for (int a = 0; a < 8; ++a) {
        for (int b = 0; b < 8; ++b) {
            const glm::vec3 p((a & 1) ? region.max.x : region.min.x,
                              (a & 2) ? region.max.y : region.min.y,
                              (a & 4) ? region.max.z : region.min.z);
            const glm::vec3 q((b & 1) ? box.max.x : box.min.x, (b & 2) ? box.max.y : box.min.y,
                              (b & 4) ? box.max.z : box.min.z);
            if (!segment_through_box(p, q, solid)) {
                return false;
            }
        }
    }
    return true;
}

TEST(ShaftOcclusion, TheShaftBoxTestAnswersAsItsSixtyFourSegments) {
    // shaft_blocked_by_box() works each axis's values out once per pair of sides (four
    // at a time with SSE2; shaft_blocked_by_box_scalar() one at a time); their slow twin
    // is the corner argument itself: segment_through_box() for each of the 64 segments
    // between the two boxes' corners. Coordinates on a coarse lattice make many flat
    // axes (a segment parallel to a face), shared planes and flat boxes.
    const auto both = [](const Aabb& region, const Aabb& box, const Aabb& solid) {
        const bool scalar = shaft_blocked_by_box_scalar(region, box, solid);
        EXPECT_EQ(shaft_blocked_by_box(region, box, solid), scalar);
        return scalar;
    };
    std::mt19937 rng(43);
    std::uniform_int_distribution<int> lattice(-12, 12);
    std::uniform_int_distribution<int> extent(0, 6);
    std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
    const auto random_box = [&](float unit, bool jittered) {
        glm::vec3 lo(0.0f);
        glm::vec3 hi(0.0f);
        for (int a = 0; a < 3; ++a) {
            lo[a] = unit * static_cast<float>(lattice(rng)) + (jittered ? jitter(rng) : 0.0f);
            hi[a] = lo[a] + unit * static_cast<float>(extent(rng));
        }
        return Aabb{lo, hi};
    };
    int blocked = 0;
    int open = 0;
    int subnormal_blocked = 0;
    int subnormal_open = 0;
    for (int i = 0; i < 200000; ++i) {
        const bool jittered = i % 4 == 3;
        const float unit = i % 2 == 0 ? 16.0f : 1.0f / 64.0f; // the shrink's own scale too
        const Aabb region = random_box(unit, jittered);
        const Aabb box = random_box(unit, jittered);
        Aabb solid = random_box(unit, false);
        solid.max += glm::vec3(unit * 4.0f);
        if (i % 3 == 0) { // a wall across one axis, mostly between them: many blocks
            const int k = i % 9 == 0 ? 0 : (i % 9 == 3 ? 1 : 2);
            for (int a = 0; a < 3; ++a) {
                solid.min[a] = a == k ? unit * static_cast<float>(lattice(rng) / 4) : -20.0f * unit;
                solid.max[a] = a == k ? solid.min[a] + unit * static_cast<float>(1 + extent(rng))
                                      : 20.0f * unit;
            }
        }
        const bool twin = every_corner_segment_through(region, box, solid);
        const bool fast = both(region, box, solid);
        ASSERT_EQ(fast, twin) << "case " << i;
        (fast ? blocked : open) += 1;
    }
    // Off the lattice: arbitrary floats up to 2^15 units, where rounding decides, and
    // corners nudged by one ulp onto either side of the solid's shrunk faces.
    std::uniform_real_distribution<float> coordinate(-32768.0f, 32768.0f);
    std::uniform_real_distribution<float> span(0.0f, 2048.0f);
    for (int i = 0; i < 100000; ++i) {
        const auto any_box = [&] {
            const glm::vec3 lo(coordinate(rng), coordinate(rng), coordinate(rng));
            return Aabb{lo, lo + glm::vec3(span(rng), span(rng), span(rng))};
        };
        Aabb solid = any_box();
        Aabb region = any_box();
        Aabb box = any_box();
        if (i % 2 == 0) { // a side of each box on a shrunk face of the solid, within an ulp
            const int a = i % 3;
            const auto nudge = [&](float v) {
                const int k = static_cast<int>(rng() % 3);
                return k == 0 ? v : std::nextafter(v, k == 1 ? 1.0e9f : -1.0e9f);
            };
            region.max[a] = std::max(region.min[a], nudge(solid.min[a] + kBoxShrink));
            box.min[a] = std::min(box.max[a], nudge(solid.max[a] - kBoxShrink));
        }
        const bool twin = every_corner_segment_through(region, box, solid);
        ASSERT_EQ(both(region, box, solid), twin) << "off-lattice case " << i;
    }
    // Sides a subnormal apart at 0, where a shrunk face of the solid may lie too:
    // 1 / (b - a) overflows to infinity there, and 0 times it is NaN.
    for (int i = 0; i < 20000; ++i) {
        const int a = i % 3;
        const int face = (i / 3) % 3; // the shrunk face at 0: the min side, the max, neither
        Aabb solid{{-8.0f, -8.0f, -8.0f}, {8.0f, 8.0f, 8.0f}};
        solid.min[a] = face == 0 ? -kBoxShrink : -16.0f;
        solid.max[a] = face == 1 ? kBoxShrink : 16.0f;
        // Inside the solid on the other axes (mostly), so that this axis decides.
        const float reach = i % 4 < 3 ? 7.0f : 30.0f;
        std::uniform_real_distribution<float> within(-reach, reach);
        const auto inner_box = [&] {
            const glm::vec3 p(within(rng), within(rng), within(rng));
            const glm::vec3 q(within(rng), within(rng), within(rng));
            return Aabb{glm::min(p, q), glm::max(p, q)};
        };
        Aabb region = inner_box();
        Aabb box = inner_box();
        const float tiny = std::numeric_limits<float>::denorm_min() * static_cast<float>(1 + i % 5);
        const float step = (i / 9) % 2 == 0 ? tiny : -tiny;
        region.min[a] = region.max[a] = 0.0f;
        box.min[a] = box.max[a] = step;
        if ((i / 18) % 2 == 0) {
            std::swap(region, box);
        }
        const bool twin = every_corner_segment_through(region, box, solid);
        const bool fast = both(region, box, solid);
        ASSERT_EQ(fast, twin) << "subnormal case " << i;
        (fast ? blocked : open) += 1;
        (fast ? subnormal_blocked : subnormal_open) += 1;
    }
    EXPECT_GT(subnormal_blocked, 2000);
    EXPECT_GT(subnormal_open, 2000);
    // Every side from a few special values on every axis at once: zeros, subnormal
    // steps both ways, the solid's shrunk faces (at 0 on some axes) and their
    // neighbouring floats, so that slab times are infinite or NaN in several lanes and
    // axes together, entering and leaving.
    const float tiny = std::numeric_limits<float>::denorm_min();
    int special_blocked = 0;
    int special_open = 0;
    for (int i = 0; i < 100000; ++i) {
        Aabb solid{{-8.0f, -8.0f, -8.0f}, {8.0f, 8.0f, 8.0f}};
        for (int a = 0; a < 3; ++a) {
            const int face = static_cast<int>(rng() % 3);
            solid.min[a] = face == 0 ? -kBoxShrink : -8.0f;
            solid.max[a] = face == 1 ? kBoxShrink : 8.0f;
        }
        const auto special = [&](int a) {
            const float lo = solid.min[a] + kBoxShrink;
            const float hi = solid.max[a] - kBoxShrink;
            const std::array<float, 12> values{0.0f,
                                               tiny,
                                               -tiny,
                                               2.0f * tiny,
                                               -2.0f * tiny,
                                               lo,
                                               hi,
                                               std::nextafter(lo, -1.0e9f),
                                               std::nextafter(hi, 1.0e9f),
                                               3.0f,
                                               -3.0f,
                                               20.0f};
            return values[rng() % values.size()];
        };
        const auto special_box = [&] {
            Aabb b;
            for (int a = 0; a < 3; ++a) {
                const float u = special(a);
                const float v = special(a);
                b.min[a] = std::min(u, v);
                b.max[a] = std::max(u, v);
            }
            return b;
        };
        const Aabb region = special_box();
        const Aabb box = special_box();
        const bool twin = every_corner_segment_through(region, box, solid);
        const bool fast = both(region, box, solid);
        ASSERT_EQ(fast, twin) << "special case " << i;
        (fast ? special_blocked : special_open) += 1;
    }
    EXPECT_GT(special_blocked, 1000);
    EXPECT_GT(special_open, 1000);
    // Outside the contract (a world's boxes are finite) the two paths still answer
    // alike, which needs every lane's min and max to pick as the scalar std::min and
    // std::max do: infinite and NaN sides among a few special ones.
    const float inf = std::numeric_limits<float>::infinity();
    const std::array<float, 8> odd{0.0f, tiny, -tiny, inf, -inf, std::nanf(""), 5.0f, -5.0f};
    for (int i = 0; i < 100000; ++i) {
        const auto odd_box = [&] {
            Aabb b;
            for (int a = 0; a < 3; ++a) {
                b.min[a] = odd[rng() % odd.size()];
                b.max[a] = odd[rng() % odd.size()];
            }
            return b;
        };
        const Aabb solid{{-8.0f, -8.0f, -kBoxShrink}, {kBoxShrink, 8.0f, 8.0f}};
        const Aabb region = odd_box();
        const Aabb box = odd_box();
        ASSERT_EQ(shaft_blocked_by_box(region, box, solid),
                  shaft_blocked_by_box_scalar(region, box, solid))
            << "odd case " << i;
    }
    EXPECT_GT(blocked, 20000); // both answers are common
    EXPECT_GT(open, 20000);
}

TEST(ShaftOcclusion, APaperThinWallIsLeftToThePlanes) {
    // A wall 1/128 unit thick: shrunk by kBoxShrink it would turn inside out, a slab
    // 3/128 wide around it, and "block" segments that run beside it in the open. The
    // world leaves it to the planes, which see that these segments never touch it.
    OccluderWorld world;
    world.add(ConvexPolyhedron::from_aabb({{0, -100, -100}, {1.0f / 128.0f, 100, 100}}));
    world.add(ConvexPolyhedron::from_aabb({{0, -100, -100}, {1.0f / 16.0f, 100, 100}}));
    EXPECT_TRUE(world.solid_box(0).is_empty());
    EXPECT_FALSE(world.solid_box(1).is_empty()); // thick enough for the fast path
    const OccluderGrid grid(world, 128.0f);
    const ShaftOcclusion shaft(world, grid, true, 0);
    ShaftOcclusion::Scratch scratch;
    // Region and box in the open just beside the thin wall (x 0.009 .. 0.015), across it
    // (y -50 to 50): every segment between them runs outside it.
    const Aabb region{{0.009f, -51, -1}, {0.012f, -49, 1}};
    const Aabb box{{0.0125f, 49, -1}, {0.015f, 51, 1}};
    std::uint32_t hint = 1; // the thin wall named as last time's blocker
    EXPECT_EQ(shaft.test(region, box, scratch, &hint), Visibility::visible);
    // Through both walls, the thin one proves it by its planes.
    const Aabb behind{{50, -1, -1}, {52, 1, 1}};
    hint = 1;
    EXPECT_EQ(shaft.test(Aabb{{-52, -1, -1}, {-50, 1, 1}}, behind, scratch, &hint),
              Visibility::occluded);
    EXPECT_EQ(hint, 1u);
}

TEST(ShaftOcclusion, AHintNamesTheBlockerAndIsTriedFirst) {
    OccluderWorld world;
    world.add(ConvexPolyhedron::from_aabb({{-8, -500, -500}, {8, 500, 500}})); // wall
    world.add(ConvexPolyhedron::from_aabb({{300, 300, -10}, {320, 320, 10}})); // crate
    const OccluderGrid grid(world, 128.0f);
    const ShaftOcclusion shaft(world, grid);
    ShaftOcclusion::Scratch scratch;
    const Aabb region{{-100, -40, -40}, {-50, 40, 40}};
    const Aabb hidden{{50, -20, -20}, {80, 20, 20}};
    std::uint32_t hint = 0;
    EXPECT_EQ(shaft.test(region, hidden, scratch, &hint), Visibility::occluded);
    EXPECT_EQ(hint, 1u); // occluder 0, the wall
    EXPECT_EQ(shaft.test(region, hidden, scratch, &hint), Visibility::occluded);
    hint = 2; // the crate: blocks nothing here; the full test still finds the wall
    EXPECT_EQ(shaft.test(region, hidden, scratch, &hint), Visibility::occluded);
    EXPECT_EQ(hint, 1u);
    // A box the wall does not hide: the hint no longer names an occluder (with portals
    // on it may hold the portal tests' skip count, see PortalOcclusion tests).
    hint = 1;
    EXPECT_EQ(shaft.test(region, Aabb{{50, 900, -20}, {80, 940, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_TRUE(hint == 0u || (hint & ShaftOcclusion::kPortalHint) != 0u) << hint;
    hint = 1;
    const ShaftOcclusion no_portals(world, grid, true, 0);
    EXPECT_EQ(no_portals.test(region, Aabb{{50, 900, -20}, {80, 940, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_EQ(hint, 0u);
}

TEST(ShaftOcclusion, RandomRegionsNeverHideWhatAnEyeSees) {
    std::mt19937 rng(11);
    int configurations = 0;
    int culled = 0;
    int misses = 0;
    std::vector<glm::vec3> samples;
    for (int w = 0; w < 3; ++w) {
        const TestWorld tw =
            w == 0   ? make_walls_world(40u + static_cast<std::uint32_t>(w), 60, 3000.0f)
            : w == 1 ? make_corridor_world(7, 4, 4)
                     : make_city_world(3, 4, 4);
        OccluderGrid grid(tw.world);
        ShaftOcclusion shaft(tw.world, grid);
        ShaftOcclusion::Scratch scratch;
        ReferenceVisibility ref(tw.world);
        testing::for_random_region_box_pairs(
            tw, rng, 700, [&](const Aabb& region, const Aabb& box) {
                ++configurations;
                // A stale or random blocker hint changes the work, never the guarantee.
                std::uint32_t hint = static_cast<std::uint32_t>(rng() % (tw.world.size() + 1));
                const bool hinted = shaft.test(region, box, scratch, &hint) == Visibility::occluded;
                if (shaft.test(region, box, scratch) != Visibility::occluded && !hinted) {
                    return;
                }
                ++culled;
                misses += testing::seen_from_lattice(ref, region, box) ? 1 : 0;
            });
    }
    EXPECT_EQ(misses, 0) << "of " << culled << " culled";
    // It must cull something: a meaningful share of random configurations.
    EXPECT_GT(culled, configurations / 20) << culled << " of " << configurations;
    std::printf("shaft stage: %d configurations, %d culled, %d misses\n", configurations, culled,
                misses);
}

} // namespace
} // namespace dsoc::visibility
