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

/// A box whose six sides are each drawn from `values` (min and max unordered).
template <std::size_t N>
Aabb box_of_values(const std::array<float, N>& values, std::mt19937& rng) {
    Aabb b;
    for (int a = 0; a < 3; ++a) {
        b.min[a] = values[rng() % N];
        b.max[a] = values[rng() % N];
    }
    return b;
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
        const auto odd_box = [&] { return box_of_values(odd, rng); };
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

TEST(ShaftOcclusion, TheShaftPlaneTestAnswersAsItsSixtyFourSegments) {
    // shaft_blocked_by() works each plane's start and rate terms out once and tests two
    // segments at a time (with SSE2); shaft_blocked_by_scalar() is its twin, one
    // segment_blocked_by() at a time. Solids of random planes around a centre (tilted,
    // like a real map's brushes), and axis planes on a coarse lattice, where many
    // segments run parallel to a plane, in it, or through a corner.
    std::mt19937 rng(47);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::uniform_int_distribution<int> lattice(-12, 12);
    std::uniform_int_distribution<int> extent(0, 6);
    const auto lattice_box = [&](float step) {
        glm::vec3 lo(0.0f);
        glm::vec3 hi(0.0f);
        for (int a = 0; a < 3; ++a) {
            lo[a] = step * static_cast<float>(lattice(rng));
            hi[a] = lo[a] + step * static_cast<float>(extent(rng));
        }
        return Aabb{lo, hi};
    };
    const auto tilted_solid = [&](glm::vec3 centre, float radius, int faces) {
        std::vector<Plane> planes;
        while (static_cast<int>(planes.size()) < faces) {
            const glm::vec3 n(unit(rng), unit(rng), unit(rng));
            if (glm::length(n) < 0.2f) {
                continue;
            }
            Plane p;
            p.normal = glm::normalize(n);
            p.distance = glm::dot(p.normal, centre) + radius;
            planes.push_back(p);
        }
        return planes;
    };
    int blocked = 0;
    int open = 0;
    for (int i = 0; i < 60000; ++i) {
        std::vector<Plane> planes;
        Aabb region;
        Aabb box;
        if (i % 2 == 0) {
            // A tilted solid between two boxes on either side of it, often hiding one
            // from the other; 4 to 40 faces (over 32 take the scalar path).
            const glm::vec3 centre(unit(rng) * 50.0f, unit(rng) * 50.0f, unit(rng) * 50.0f);
            const int faces = i % 100 == 0 ? 40 : 4 + static_cast<int>(rng() % 14);
            planes = tilted_solid(centre, 60.0f + 60.0f * unit(rng), faces);
            const glm::vec3 axis =
                glm::normalize(glm::vec3(unit(rng), unit(rng), 0.3f * unit(rng)));
            const auto near = [&](float along) {
                const glm::vec3 c =
                    centre + axis * along + glm::vec3(unit(rng), unit(rng), unit(rng)) * 40.0f;
                const glm::vec3 half(8.0f + 30.0f * std::abs(unit(rng)),
                                     8.0f + 30.0f * std::abs(unit(rng)),
                                     8.0f + 30.0f * std::abs(unit(rng)));
                return Aabb{c - half, c + half};
            };
            region = near(-200.0f - 100.0f * std::abs(unit(rng)));
            box = near(200.0f + 100.0f * std::abs(unit(rng)));
        } else {
            // Axis planes on a lattice: flat rates, starts of exactly zero.
            const float step = i % 4 == 1 ? 16.0f : 1.0f / 64.0f;
            Aabb solid = lattice_box(step);
            solid.max += glm::vec3(step * 4.0f);
            planes = ConvexPolyhedron::from_aabb(solid).planes();
            region = lattice_box(step);
            box = lattice_box(step);
        }
        const bool scalar = shaft_blocked_by_scalar(region, box, planes);
        ASSERT_EQ(shaft_blocked_by(region, box, planes), scalar) << "case " << i;
        (scalar ? blocked : open) += 1;
    }
    EXPECT_GT(blocked, 8000); // both answers are common
    EXPECT_GT(open, 8000);
    // Outside the contract (a world's boxes are finite) the two paths still answer alike,
    // which needs every lane's min and max to pick as the scalar std::min and std::max
    // do: infinite, NaN and subnormal sides, and planes with zero and subnormal normals.
    const float inf = std::numeric_limits<float>::infinity();
    const float tiny = std::numeric_limits<float>::denorm_min();
    // (1e17 and 1 make sums that depend on their order, though no case here has been
    // seen to turn on the rate's: a rate summed in another order is not caught.)
    const std::array<float, 12> odd{0.0f, tiny,  -tiny, inf,     -inf,     std::nanf(""),
                                    5.0f, -5.0f, 40.0f, 1.0e17f, -1.0e17f, 1.0f};
    int odd_blocked = 0;
    for (int i = 0; i < 200000; ++i) {
        const auto odd_box = [&] { return box_of_values(odd, rng); };
        // A cube's faces and up to three odd planes, in a random order (a NaN time that
        // the scalar path drops must not stick in a lane, whichever plane comes last).
        std::vector<Plane> planes = ConvexPolyhedron::from_aabb({{-8, -8, -8}, {8, 8, 8}}).planes();
        for (int k = static_cast<int>(rng() % 4); k > 0; --k) {
            Plane p;
            p.normal = glm::vec3(odd[rng() % odd.size()], odd[rng() % odd.size()],
                                 odd[rng() % odd.size()]);
            p.distance = odd[rng() % odd.size()];
            planes.push_back(p);
        }
        std::shuffle(planes.begin(), planes.end(), rng);
        const Aabb region = odd_box();
        const Aabb box = odd_box();
        const bool scalar = shaft_blocked_by_scalar(region, box, planes);
        ASSERT_EQ(shaft_blocked_by(region, box, planes), scalar) << "odd case " << i;
        odd_blocked += scalar ? 1 : 0;
    }
    EXPECT_GT(odd_blocked, 100);
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
    // on it may hold the portal tests' skip count, see PortalOcclusion tests; the wall
    // blocks the centre segment, so without them it names a witness, tested below).
    hint = 1;
    EXPECT_EQ(shaft.test(region, Aabb{{50, 900, -20}, {80, 940, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_TRUE(hint == 0u || (hint & ShaftOcclusion::kPortalHint) != 0u) << hint;
    hint = 1;
    const ShaftOcclusion no_portals(world, grid, true, 0);
    EXPECT_EQ(no_portals.test(region, Aabb{{50, 900, -20}, {80, 940, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_NE(hint, 1u);
    EXPECT_EQ(hint & ~ShaftOcclusion::kWitnessCorners, ShaftOcclusion::kWitnessHint) << hint;
    // Clear of the wall on both sides: no witness (the next test walks the centre first).
    hint = 0;
    EXPECT_EQ(no_portals.test(region, Aabb{{-90, 900, -20}, {-60, 940, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_EQ(hint, 0u);
}

glm::vec3 corner_of(const Aabb& b, std::uint32_t k) {
    return {(k & 1) ? b.max.x : b.min.x, (k & 2) ? b.max.y : b.min.y, (k & 4) ? b.max.z : b.min.z};
}

TEST(ShaftOcclusion, AWitnessSegmentShowsABoxInViewUntilItIsBlocked) {
    OccluderWorld world;
    world.add(ConvexPolyhedron::from_aabb({{-8, -500, -500}, {8, 500, 500}})); // wall
    const OccluderGrid grid(world, 128.0f);
    const ShaftOcclusion shaft(world, grid, true, 0);
    ShaftOcclusion::Scratch scratch;
    ReferenceVisibility ref(world);
    const Aabb region{{-100, -40, -40}, {-50, 40, 40}};
    const Aabb beside{{50, 900, -20}, {80, 940, 20}}; // the wall blocks the centre segment
    std::uint32_t hint = 0;
    ASSERT_EQ(shaft.test(region, beside, scratch, &hint), Visibility::visible);
    ASSERT_EQ(hint & ~ShaftOcclusion::kWitnessCorners, ShaftOcclusion::kWitnessHint) << hint;
    const std::uint32_t found = hint;
    EXPECT_FALSE(
        ref.segment_blocked(corner_of(region, (found >> 3) & 7u), corner_of(beside, found & 7u)));
    // A clear witness answers by itself: one the search never picks (lower corners)
    // stays as it is, where the full test would have found the search's own again.
    const std::uint32_t lower = ShaftOcclusion::kWitnessHint | 0u << 3 | 0u;
    ASSERT_FALSE(ref.segment_blocked(corner_of(region, 0), corner_of(beside, 0)));
    ASSERT_NE(lower, found);
    hint = lower;
    EXPECT_EQ(shaft.test(region, beside, scratch, &hint), Visibility::visible);
    EXPECT_EQ(hint, lower);
    // Blocked now (the box moved behind the wall): dropped, and the full test proves
    // the box hidden and names the wall.
    const Aabb behind{{50, -20, -20}, {80, 20, 20}};
    hint = found;
    EXPECT_EQ(shaft.test(region, behind, scratch, &hint), Visibility::occluded);
    EXPECT_EQ(hint, 1u);
    // Blocked but the box still in view (it moved along the wall's end): dropped, and
    // the full test answers `visible` with a witness of its own.
    const Aabb along{{50, 820, -20}, {80, 860, 20}};
    ASSERT_TRUE(ref.segment_blocked(corner_of(region, 0), corner_of(along, 0)));
    hint = lower;
    EXPECT_EQ(shaft.test(region, along, scratch, &hint), Visibility::visible);
    EXPECT_NE(hint, lower);
    EXPECT_EQ(hint & ~ShaftOcclusion::kWitnessCorners, ShaftOcclusion::kWitnessHint) << hint;
    EXPECT_EQ(shaft.test(region, along, scratch), Visibility::visible);
    // A box over kMaxPortalBoxSide (an entity cluster's) is not searched: its hint is
    // not kept while it is visible.
    hint = 0;
    EXPECT_EQ(shaft.test(region, Aabb{{50, 820, -20}, {300, 1060, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_EQ(hint, 0u);
}

TEST(ShaftOcclusion, AWitnessGrazingAFaceDoesNotShowAHiddenBox) {
    // The upper corners' segment runs 1/100 unit inside the wall's end face: inside the
    // solid, yet outside it shrunk by kBoxShrink, so the single-occluder test does not
    // hide the box, and fusion on the plane y = 0 does. A witness must keep clear of
    // the face by more than that slack, or it would show the hidden box.
    OccluderWorld world;
    world.add(ConvexPolyhedron::from_aabb({{-500, -8, -500}, {10, 8, 500}}));
    const OccluderGrid grid(world, 128.0f);
    const ShaftOcclusion shaft(world, grid, true, 0);
    ShaftOcclusion::Scratch scratch;
    const Aabb region{{-40, -100, -10}, {9.99f, -60, 10}};
    const Aabb box{{-40, 60, -10}, {9.99f, 100, 10}};
    ASSERT_EQ(shaft.test(region, box, scratch), Visibility::occluded);
    std::uint32_t hint = ShaftOcclusion::kWitnessHint | 7u << 3 | 7u;
    EXPECT_EQ(shaft.test(region, box, scratch, &hint), Visibility::occluded);
}

TEST(ShaftOcclusion, SearchesForAWitnessThatKeepFailingAreSpaced) {
    // A low wall blocks the centre segment and a beam above it blocks the upper corners'
    // segments; the box is seen through the slot between them (z 2 to 10), so it is
    // visible with no witness among the corners searched.
    OccluderWorld world;
    world.add(ConvexPolyhedron::from_aabb({{-8, -500, -200}, {8, 500, 2}})); // low wall
    world.add(ConvexPolyhedron::from_aabb({{-8, -500, 10}, {8, 500, 200}})); // beam
    const OccluderGrid grid(world, 128.0f);
    const ShaftOcclusion shaft(world, grid, true, 0);
    ShaftOcclusion::Scratch scratch;
    const Aabb region{{-100, -40, -40}, {-50, 40, 40}};
    const Aabb box{{50, -20, -20}, {80, 20, 20}};
    const auto no_witness = [](std::uint32_t level, std::uint32_t skips) {
        return ShaftOcclusion::kWitnessHint | ShaftOcclusion::kNoWitness | level << 4 | skips;
    };
    // Searched and failed: skip the next one; then search and fail again: skip three,
    // then seven, then fifteen, and stay there.
    const std::array<std::uint32_t, 12> expected{
        no_witness(0, 1), no_witness(0, 0), no_witness(1, 3), no_witness(1, 2),
        no_witness(1, 1), no_witness(1, 0), no_witness(2, 7), no_witness(2, 6),
        no_witness(2, 5), no_witness(2, 4), no_witness(2, 3), no_witness(2, 2)};
    std::uint32_t hint = 0;
    for (std::size_t t = 0; t < expected.size(); ++t) {
        ASSERT_EQ(shaft.test(region, box, scratch, &hint), Visibility::visible) << "test " << t;
        ASSERT_EQ(hint, expected[t]) << "test " << t;
    }
    hint = no_witness(3, 0);
    EXPECT_EQ(shaft.test(region, box, scratch, &hint), Visibility::visible);
    EXPECT_EQ(hint, no_witness(3, 15));
    // The record is dropped once the box is hidden (the hint names the blocker) or its
    // centre segment is clear.
    hint = no_witness(1, 2);
    EXPECT_EQ(shaft.test(region, Aabb{{50, -20, 100}, {80, 20, 140}}, scratch, &hint),
              Visibility::occluded);
    EXPECT_EQ(hint, 2u); // the beam
    hint = no_witness(1, 2);
    EXPECT_EQ(shaft.test(region, Aabb{{-90, 900, -20}, {-60, 940, 20}}, scratch, &hint),
              Visibility::visible);
    EXPECT_EQ(hint, 0u);
}

TEST(ShaftOcclusion, AWitnessNeverShowsWhatTheFullTestHides) {
    // Pairs moving a few units a step, each carrying its hint from test to test as the
    // manager does: a kept witness is a clear segment (brute force over every occluder)
    // and the full test without a hint answers `visible` too, so witnesses cost no
    // entity a full test would hide. Portal depths 0 and 2.
    std::mt19937 rng(53);
    int kept = 0;
    int hidden = 0;
    int tests = 0;
    for (int w = 0; w < 3; ++w) {
        const TestWorld tw = w == 0   ? make_walls_world(41u, 60, 3000.0f)
                             : w == 1 ? make_corridor_world(7, 4, 4)
                                      : make_city_world(3, 4, 4);
        const OccluderGrid grid(tw.world);
        ReferenceVisibility ref(tw.world);
        for (const int depth : {0, 2}) {
            const ShaftOcclusion shaft(tw.world, grid, true, depth);
            ShaftOcclusion::Scratch scratch;
            testing::for_random_region_box_pairs(tw, rng, 150, [&](Aabb region, Aabb box) {
                std::uint32_t hint = 0;
                for (int t = 0; t < 12; ++t) {
                    testing::step_pair(rng, 6.0f, region, box);
                    const std::uint32_t before = hint;
                    const Visibility seen = shaft.test(region, box, scratch, &hint);
                    ++tests;
                    hidden += seen == Visibility::occluded ? 1 : 0;
                    const bool witness =
                        (before & ~ShaftOcclusion::kWitnessCorners) == ShaftOcclusion::kWitnessHint;
                    if (!witness || seen != Visibility::visible || hint != before) {
                        continue;
                    }
                    ++kept;
                    ASSERT_FALSE(ref.segment_blocked(corner_of(region, (hint >> 3) & 7u),
                                                     corner_of(box, hint & 7u)));
                    ASSERT_EQ(shaft.test(region, box, scratch), Visibility::visible)
                        << "world " << w << " depth " << depth;
                }
            });
        }
    }
    EXPECT_GT(kept, tests / 50) << kept << " of " << tests;
    EXPECT_GT(hidden, tests / 10) << hidden << " of " << tests;
    std::printf("witnesses: %d tests, %d kept, %d hidden\n", tests, kept, hidden);
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
                // A stale or random blocker or witness hint changes the work, never the
                // guarantee.
                std::uint32_t hint =
                    rng() % 4 == 0
                        ? ShaftOcclusion::kWitnessHint | static_cast<std::uint32_t>(rng() % 64)
                        : static_cast<std::uint32_t>(rng() % (tw.world.size() + 1));
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
