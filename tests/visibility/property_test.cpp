// Randomized property test: both culling backends against the brute-force reference.
// Whenever the reference finds an unblocked segment from the eye to a sample of the
// box, both the z-pyramid and the beams must answer `visible` (zero misses). And each
// must cull a stated minimum share of the boxes the reference finds hidden, so the
// test cannot pass by answering `visible` always.

#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/combined_tester.hpp"
#include "dsoc/visibility/seeds/occlusion_beams.hpp"
#include "dsoc/visibility/seeds/occlusion_buffer.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include "test_scene.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>

namespace dsoc::visibility {
namespace {

struct Tally {
    int configs = 0;
    int reference_visible = 0;
    int reference_hidden = 0;
    int buffer_misses = 0; ///< buffer said occluded, reference saw it: must stay 0
    int beam_misses = 0;
    int buffer_culled = 0; ///< buffer said occluded (all correct when misses == 0)
    int beam_culled = 0;
    int either_culled = 0; ///< EitherOccludes(buffer, beams)
    int either_misses = 0;

    Tally& operator+=(const Tally& t) {
        configs += t.configs;
        reference_visible += t.reference_visible;
        reference_hidden += t.reference_hidden;
        buffer_misses += t.buffer_misses;
        beam_misses += t.beam_misses;
        buffer_culled += t.buffer_culled;
        beam_culled += t.beam_culled;
        either_culled += t.either_culled;
        either_misses += t.either_misses;
        return *this;
    }
};

bool inside_any(const OccluderWorld& world, glm::vec3 p) {
    for (const auto& o : world.occluders()) {
        if (o.contains(p, 0.5f)) {
            return true;
        }
    }
    return false;
}

/// `eyes` eyes x `boxes` boxes in one world. Eyes are random free points, half of
/// them pushed next to an occluder surface; boxes are random, some snapped so a face
/// lies in one of the eye's axis planes (cube seams), some tiny, some large.
void run_world(const char* name, const TestWorld& tw, std::uint32_t seed, int eyes, int boxes,
               Tally& total, const OcclusionBufferConfig& config = {}) {
    BspTree bsp;
    bsp.build(tw.world);
    const ReferenceVisibility reference(tw.world);
    OcclusionBuffer buffer(config);
    OcclusionBeams beams;
    testing::WorldDice dice(tw.play_area, seed);
    Tally t;
    for (int e = 0; e < eyes; ++e) {
        glm::vec3 eye = dice.point();
        const auto& o = tw.world.occluder(static_cast<OccluderId>(dice.rng() % tw.world.size()));
        if (e % 3 == 1) {
            // Next to an occluder: a point just outside a random vertex.
            const glm::vec3 v = o.vertices()[dice.rng() % o.vertices().size()];
            const glm::vec3 c = o.bounding_sphere().center;
            eye = v + (v - c) * (0.01f + 0.3f * dice.unit());
        } else if (e % 3 == 2) {
            // In (or a hair off) the plane of one of its faces: grazing views.
            const Plane& p = o.faces()[dice.rng() % o.faces().size()].plane;
            eye -= p.normal * p.signed_distance(eye);
            eye += p.normal * (dice.unit() < 0.5f ? 0.0f : 0.01f * dice.unit());
        }
        if (inside_any(tw.world, eye)) {
            --e;
            continue;
        }
        buffer.build(eye, tw.world, bsp);
        beams.build(eye, tw.world, bsp);
        for (int b = 0; b < boxes; ++b) {
            Aabb box =
                testing::random_test_box(dice, tw.world, b, {0.5f, 4.0f, 40.0f, 64.0f, 128.0f});
            if (b % 5 == 0) {
                // Snap one face onto an axis plane through the eye (a cube-face seam).
                const int axis = static_cast<int>(dice.rng() % 3);
                const float shift = eye[axis] - box.min[axis];
                box.min[axis] += shift;
                box.max[axis] += shift;
            }
            const Visibility truth = reference.test_box(eye, box, 5);
            const Visibility zb = buffer.test_box(box);
            const Visibility bm = beams.test_box(box);
            const Visibility either = EitherOccludes(buffer, beams).test_box(box);
            EXPECT_EQ(either == Visibility::occluded,
                      zb == Visibility::occluded || bm == Visibility::occluded);
            t.either_culled += either == Visibility::occluded;
            ++t.configs;
            t.buffer_culled += zb == Visibility::occluded;
            t.beam_culled += bm == Visibility::occluded;
            if (truth == Visibility::visible) {
                ++t.reference_visible;
                if (zb == Visibility::occluded) {
                    ++t.buffer_misses;
                    ADD_FAILURE() << name << ": z-pyramid culled a visible box; eye "
                                  << testing::text(eye) << " box " << testing::text(box);
                }
                if (bm == Visibility::occluded) {
                    ++t.beam_misses;
                    ADD_FAILURE() << name << ": beams culled a visible box; eye "
                                  << testing::text(eye) << " box " << testing::text(box);
                }
            } else {
                ++t.reference_hidden;
            }
        }
    }
    std::printf("[ property ] %-9s %5d configs: reference hidden %5d; z-pyramid culls %5d "
                "(%.1f%% of hidden), beams cull %5d (%.1f%%); misses %d / %d\n",
                name, t.configs, t.reference_hidden, t.buffer_culled,
                100.0 * t.buffer_culled / std::max(1, t.reference_hidden), t.beam_culled,
                100.0 * t.beam_culled / std::max(1, t.reference_hidden), t.buffer_misses,
                t.beam_misses);
    total += t;
}

TEST(VisibilityProperty, BackendsNeverCullWhatTheReferenceSees) {
    Tally total;
    // Default settings: 4 worlds x 60 eyes x 100 boxes.
    run_world("random", make_random_world(11, 150, 2048.0f), 101, 60, 100, total);
    run_world("walls", make_walls_world(12, 60, 3000.0f), 102, 60, 100, total);
    run_world("corridor", make_corridor_world(13, 4, 4), 103, 60, 100, total);
    run_world("city", make_city_world(14, 4, 4), 104, 60, 100, total);
    std::printf("[ property ] total     %5d configs: reference hidden %5d; z-pyramid culls %5d "
                "(%.1f%%), beams cull %5d (%.1f%%), either %5d (%.1f%%)\n",
                total.configs, total.reference_hidden, total.buffer_culled,
                100.0 * total.buffer_culled / std::max(1, total.reference_hidden),
                total.beam_culled, 100.0 * total.beam_culled / std::max(1, total.reference_hidden),
                total.either_culled,
                100.0 * total.either_culled / std::max(1, total.reference_hidden));
    EXPECT_GE(total.configs, 10000);
    EXPECT_EQ(total.buffer_misses, 0);
    EXPECT_EQ(total.beam_misses, 0);
    // Both outcomes must be well represented for the test to mean anything.
    EXPECT_GT(total.reference_hidden, total.configs / 5);
    EXPECT_GT(total.reference_visible, total.configs / 5);
    // Minimum cull rates, as a share of the boxes the reference finds hidden
    // (measured: z-pyramid 90%, beams 93%, either 97%).
    EXPECT_GE(total.buffer_culled, total.reference_hidden * 80 / 100);
    EXPECT_GE(total.beam_culled, total.reference_hidden * 75 / 100);
    EXPECT_GE(total.either_culled, std::max(total.buffer_culled, total.beam_culled));
}

TEST(VisibilityProperty, OtherResolutionsAreConservativeToo) {
    for (const int resolution : {8, 32, 256}) {
        OcclusionBufferConfig config;
        config.face_resolution = resolution;
        Tally total;
        run_world("random", make_random_world(21, 150, 2048.0f), 201, 12, 100, total, config);
        run_world("corridor", make_corridor_world(23, 4, 4), 203, 12, 100, total, config);
        run_world("city", make_city_world(24, 3, 3), 204, 12, 100, total, config);
        std::printf("[ property ] resolution %d: %d configs, z-pyramid culls %.1f%% of hidden\n",
                    resolution, total.configs,
                    100.0 * total.buffer_culled / std::max(1, total.reference_hidden));
        EXPECT_EQ(total.buffer_misses, 0) << "resolution " << resolution;
        EXPECT_EQ(total.beam_misses, 0);
        EXPECT_GT(total.buffer_culled, 0);
    }
}

} // namespace
} // namespace dsoc::visibility

namespace dsoc::visibility {
namespace {

/// From-region mode: the buffer built for a viewer region must answer `visible`
/// whenever the reference sees the box from any sampled eye of the region (its 8
/// corners, its centre and random interior points).
void run_region_world(const char* name, const TestWorld& tw, std::uint32_t seed, int regions,
                      int boxes, Tally& total) {
    BspTree bsp;
    bsp.build(tw.world);
    const ReferenceVisibility reference(tw.world);
    OcclusionBuffer buffer;
    testing::WorldDice dice(tw.play_area, seed);
    Tally t;
    std::vector<glm::vec3> eyes;
    for (int r = 0; r < regions; ++r) {
        const glm::vec3 c = dice.point();
        const glm::vec3 half(8.0f + 40.0f * dice.unit(), 8.0f + 40.0f * dice.unit(),
                             16.0f * dice.unit());
        const Aabb region = Aabb::from_center_half_extents(c, half);
        eyes.clear();
        for (int j = 0; j < 8; ++j) {
            eyes.emplace_back((j & 1) ? region.max.x : region.min.x,
                              (j & 2) ? region.max.y : region.min.y,
                              (j & 4) ? region.max.z : region.min.z);
        }
        eyes.push_back(c);
        for (int k = 0; k < 8; ++k) {
            eyes.push_back(region.min +
                           region.size() * glm::vec3(dice.unit(), dice.unit(), dice.unit()));
        }
        buffer.build_region(region, tw.world, bsp);
        for (int b = 0; b < boxes; ++b) {
            const float h = 4.0f + 40.0f * dice.unit();
            const Aabb box =
                Aabb::from_center_half_extents(dice.point(), glm::vec3(h, h, h * 1.5f));
            bool seen = false;
            for (const glm::vec3& e : eyes) {
                seen = seen || reference.test_box(e, box, 4) == Visibility::visible;
            }
            const Visibility answer = buffer.test_box(box);
            ++t.configs;
            t.buffer_culled += answer == Visibility::occluded;
            if (seen) {
                ++t.reference_visible;
                if (answer == Visibility::occluded) {
                    ++t.buffer_misses;
                    ADD_FAILURE() << name << ": region buffer culled a box seen from the region";
                }
            } else {
                ++t.reference_hidden;
            }
        }
    }
    std::printf("[ region   ] %-9s %5d configs: hidden from all sampled eyes %5d; region z-pyramid "
                "culls %5d (%.1f%%); misses %d\n",
                name, t.configs, t.reference_hidden, t.buffer_culled,
                100.0 * t.buffer_culled / std::max(1, t.reference_hidden), t.buffer_misses);
    total += t;
}

TEST(VisibilityProperty, RegionBufferCoversEveryEyeOfTheRegion) {
    Tally total;
    run_region_world("random", make_random_world(31, 150, 2048.0f), 301, 20, 60, total);
    run_region_world("walls", make_walls_world(32, 60, 3000.0f), 302, 20, 60, total);
    run_region_world("corridor", make_corridor_world(33, 4, 4), 303, 20, 60, total);
    run_region_world("city", make_city_world(34, 4, 4), 304, 20, 60, total);
    EXPECT_EQ(total.buffer_misses, 0);
    EXPECT_GT(total.reference_hidden, total.configs / 5);
    EXPECT_GE(total.buffer_culled, total.reference_hidden * 30 / 100);
}

} // namespace
} // namespace dsoc::visibility

namespace dsoc::visibility {
namespace {

/// The same world moved far from the origin, where float coordinates keep only
/// ~1e-3 units of precision: the margins must still hold (plane offsets and box
/// differences are computed in double).
TestWorld translated(const TestWorld& in, glm::vec3 offset) {
    TestWorld out;
    for (const auto& o : in.world.occluders()) {
        std::vector<Plane> planes(o.planes().begin(), o.planes().end());
        for (Plane& p : planes) {
            p.distance += glm::dot(p.normal, offset);
        }
        PolyhedronResult result;
        (void)out.world.add(ConvexPolyhedron::from_planes(planes, result));
    }
    out.play_area = {in.play_area.min + offset, in.play_area.max + offset};
    return out;
}

TEST(VisibilityProperty, LargeCoordinatesStayConservative) {
    Tally total;
    const glm::vec3 offset(7000.0f, -6000.0f, 3000.0f);
    run_world("random+9k", translated(make_random_world(41, 150, 2048.0f), offset), 401, 30, 100,
              total);
    run_world("corridor+9k", translated(make_corridor_world(42, 4, 4), offset), 402, 30, 100,
              total);
    EXPECT_EQ(total.buffer_misses, 0);
    EXPECT_EQ(total.beam_misses, 0);
    EXPECT_GE(total.buffer_culled, total.reference_hidden * 70 / 100);
}

} // namespace
} // namespace dsoc::visibility
