// From-region occlusion buffer: hand-made cases, the pyramid, and a randomized
// property test against the exact segment reference with many eyes per region.

#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/region_occlusion_buffer.hpp"
#include "dsoc/visibility/seeds/occlusion_buffer.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include "test_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <thread>
#include <vector>

namespace dsoc::visibility {
namespace {

using testing::cube;
using testing::region_at;
using testing::Scene;

TEST(RegionOcclusionBuffer, WallBetweenRegionAndBoxHidesIt) {
    Scene s;
    s.add_box({200, -2000, -2000}, {216, 2000, 2000});
    s.build();
    RegionOcclusionBuffer buffer;
    buffer.build(region_at({0, 0, 0}, {48, 48, 40}), s.world, s.bsp);
    EXPECT_GT(buffer.stats().texels_written, 0);
    EXPECT_EQ(buffer.test_box(cube({400, 0, 0}, 16)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({600, 400, 100}, 16)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({150, 0, 0}, 16)), Visibility::visible);    // in front
    EXPECT_EQ(buffer.test_box(cube({-300, 0, 0}, 16)), Visibility::visible);   // behind
    EXPECT_EQ(buffer.test_box(cube({400, 5000, 0}, 16)), Visibility::visible); // past its end
    EXPECT_EQ(buffer.test_box(cube({208, 0, 0}, 20)), Visibility::visible);    // pokes out
    EXPECT_EQ(buffer.test_box(Aabb::empty()), Visibility::visible);
}

TEST(RegionOcclusionBuffer, GapSeenFromACornerButNotFromTheCentreIsVisible) {
    // A wall at x in [200, 216] with a slot y in [40, 60]. From the centre the box at
    // x = 400, y in [45, 55] is behind the wall (its rays cross x = 200 at y < 28);
    // from the region's corner at y = +48 they pass through the slot.
    Scene s;
    s.add_box({200, -2000, -2000}, {216, 40, 2000});
    s.add_box({200, 60, -2000}, {216, 2000, 2000});
    s.build();
    const Aabb target{{395, 45, -5}, {405, 55, 5}};
    const ReferenceVisibility reference(s.world);
    ASSERT_EQ(reference.test_box({0, 0, 0}, target), Visibility::occluded);
    ASSERT_EQ(reference.test_box({0, 48, 0}, target), Visibility::visible);

    OcclusionBuffer point;
    point.build({0, 0, 0}, s.world, s.bsp);
    EXPECT_EQ(point.test_box(target), Visibility::occluded); // right for the point only

    RegionOcclusionBuffer region;
    region.build(region_at({0, 0, 0}, {48, 48, 40}), s.world, s.bsp);
    EXPECT_EQ(region.test_box(target), Visibility::visible);
    // Far from the slot the wall still hides boxes from the whole region.
    EXPECT_EQ(region.test_box(cube({400, -300, 0}, 16)), Visibility::occluded);

    // The same buffer as a point (h = 0) agrees with the point buffer.
    region.build(region_at({0, 0, 0}, {0, 0, 0}), s.world, s.bsp);
    EXPECT_EQ(region.test_box(target), Visibility::occluded);
}

TEST(RegionOcclusionBuffer, RaysMeetingAnOccluderOnBothSidesOfThePlaneDoNotCount) {
    // Two plates along the x axis (y = +-33.5) reach across the +x projection plane
    // (x = D = 1024). Through the texels at y in [-32, 32] on that plane, every ray
    // from a region corner meets a plate: from the upper corners before the plane,
    // from the lower corners beyond it (or the reverse). The centre's rays pass
    // between the plates. "Every corner's unbounded ray hits O" is therefore not
    // enough: the set of eyes whose rays hit is not convex when the hits lie on
    // both sides of the plane. Only all-before or all-beyond may be written.
    Scene s;
    s.add_box({150, 33, -1000}, {1800, 34, 1000});
    s.add_box({150, -34, -1000}, {1800, -33, 1000});
    s.build();
    const Aabb target = cube({1900, 0, 0}, 8);
    const ReferenceVisibility reference(s.world);
    ASSERT_EQ(reference.test_box({0, 0, 0}, target), Visibility::visible);
    RegionOcclusionBufferConfig config;
    config.face_resolution = 64;
    config.projection_distance = 1024.0f;
    RegionOcclusionBuffer buffer(config);
    buffer.build(region_at({0, 0, 0}, {48, 48, 40}), s.world, s.bsp);
    EXPECT_EQ(buffer.test_box(target), Visibility::visible);
}

TEST(RegionOcclusionBuffer, BoxTouchingTheRegionIsVisible) {
    Scene s;
    s.add_box({200, -2000, -2000}, {216, 2000, 2000});
    s.build();
    RegionOcclusionBuffer buffer;
    buffer.build(region_at({0, 0, 0}, {48, 48, 40}), s.world, s.bsp);
    ASSERT_EQ(buffer.test_box(cube({400, 0, 0}, 16)), Visibility::occluded);
    EXPECT_EQ(buffer.test_box(cube({40, 40, 0}, 16)), Visibility::visible);
    EXPECT_EQ(buffer.test_box(Aabb{{48.5f, -5, -5}, {60, 5, 5}}), Visibility::visible);
    EXPECT_EQ(buffer.test_box(Aabb{{-1000, -1000, -1000}, {1000, 1000, 1000}}),
              Visibility::visible);
}

TEST(RegionOcclusionBuffer, OccluderTouchingTheRegionWritesNothing) {
    Scene s;
    s.add_box({30, -2000, -2000}, {46, 2000, 2000}); // inside the region's x extent
    s.build();
    RegionOcclusionBuffer buffer;
    buffer.build(region_at({0, 0, 0}, {48, 48, 40}), s.world, s.bsp);
    EXPECT_EQ(buffer.stats().occluders_visited, 1);
    EXPECT_EQ(buffer.stats().occluders_skipped_region, 1);
    EXPECT_EQ(buffer.stats().texels_written, 0);
    EXPECT_EQ(buffer.test_box(cube({400, 0, 0}, 16)), Visibility::visible);
    // The same wall 10 units outside the region is used.
    Scene t;
    t.add_box({58, -2000, -2000}, {74, 2000, 2000});
    t.build();
    buffer.build(region_at({0, 0, 0}, {48, 48, 40}), t.world, t.bsp);
    EXPECT_EQ(buffer.stats().occluders_skipped_region, 0);
    EXPECT_EQ(buffer.test_box(cube({400, 0, 0}, 16)), Visibility::occluded);
}

TEST(RegionOcclusionBuffer, PyramidLevelsHoldTheMaxOfTheirFourChildren) {
    testing::expect_pyramid_of_maxima<RegionOcclusionBuffer, RegionOcclusionBufferConfig>(
        region_at({700, 800, 60}, {48, 48, 40}));
}

TEST(RegionOcclusionBuffer, BudgetAndEmptyRegion) {
    const Scene s(make_corridor_world(5, 6, 6));
    RegionOcclusionBufferConfig config;
    config.max_occluders = 5;
    RegionOcclusionBuffer buffer(config);
    buffer.build(region_at({700, 800, 60}, {48, 48, 40}), s.world, s.bsp);
    EXPECT_EQ(buffer.stats().occluders_visited, 5);
    buffer.build(Aabb::empty(), s.world, s.bsp);
    EXPECT_EQ(buffer.stats().texels_written, 0);
    EXPECT_EQ(buffer.test_box(cube({5000, 5000, 60}, 1)), Visibility::visible);
}

TEST(RegionOcclusionBuffer, ConcurrentTestsAgreeWithSerialOnes) {
    const Scene s(make_corridor_world(6, 4, 4));
    RegionOcclusionBuffer buffer;
    buffer.build(region_at({700, 800, 60}, {48, 48, 40}), s.world, s.bsp);
    std::vector<Aabb> boxes;
    for (int i = 0; i < 400; ++i) {
        const float x = 40.0f + 5.0f * static_cast<float>(i);
        boxes.push_back(cube({x, static_cast<float>((i * 37) % 2000), 60.0f}, 12.0f));
    }
    std::vector<Visibility> serial, a(boxes.size()), b(boxes.size());
    for (const Aabb& box : boxes) {
        serial.push_back(buffer.test_box(box));
    }
    std::thread first([&] {
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            a[i] = buffer.test_box(boxes[i]);
        }
    });
    std::thread second([&] {
        for (std::size_t i = boxes.size(); i-- > 0;) {
            b[i] = buffer.test_box(boxes[i]);
        }
    });
    first.join();
    second.join();
    EXPECT_EQ(a, serial);
    EXPECT_EQ(b, serial);
    EXPECT_NE(std::count(serial.begin(), serial.end(), Visibility::occluded), 0);
}

TEST(RegionOcclusionBuffer, ValidateNamesTheField) {
    RegionOcclusionBufferConfig config;
    EXPECT_TRUE(validate(config).empty());
    config.face_resolution = 100;
    config.projection_distance = 0.0f;
    testing::expect_problems_naming(validate(config), {"face_resolution", "projection_distance"});
}

// ---------------------------------------------------------------------------------
// Randomized property test.

/// Exact segment reference restricted to the occluders near one configuration.
class LocalReference {
public:
    LocalReference(const OccluderWorld& world, const Aabb& span) : world_(&world) {
        for (OccluderId id = 0; id < world.size(); ++id) {
            if (world.occluder(id).bounds().overlaps(span)) {
                candidates_.push_back(id);
            }
        }
    }
    [[nodiscard]] bool blocked(glm::vec3 a, glm::vec3 b) const {
        Aabb seg;
        seg.extend(a);
        seg.extend(b);
        for (const OccluderId id : candidates_) {
            if (world_->occluder(id).bounds().overlaps(seg) &&
                segment_blocked_by(a, b, world_->face_planes(id))) {
                return true;
            }
        }
        return false;
    }

private:
    const OccluderWorld* world_;
    std::vector<OccluderId> candidates_;
};

/// Eye samples of a region: 8 corners, centre, 6 face centres, 12 edge midpoints and
/// `random_count` random interior points (deduplicated only by construction).
void region_samples(const Aabb& r, int random_count, std::mt19937& rng,
                    std::vector<glm::vec3>& out) {
    out.clear();
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const glm::vec3 c = r.center();
    for (int i = 0; i < 27; ++i) { // 3x3x3 lattice: corners, edge and face centres, centre
        const int ix = i % 3, iy = (i / 3) % 3, iz = i / 9;
        auto pick = [](float lo, float mid, float hi, int k) {
            return k == 0 ? lo : (k == 1 ? mid : hi);
        };
        out.emplace_back(pick(r.min.x, c.x, r.max.x, ix), pick(r.min.y, c.y, r.max.y, iy),
                         pick(r.min.z, c.z, r.max.z, iz));
    }
    for (int i = 0; i < random_count; ++i) {
        out.push_back(r.min + r.size() * glm::vec3(unit(rng), unit(rng), unit(rng)));
    }
}

/// Parallel walls (8..24 thick) with narrow vertical slits and windows (2..48 wide):
/// the parallax case, where an eye off the region's centre sees through a gap that
/// the centre cannot.
TestWorld make_slotted_walls(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    TestWorld tw;
    auto add = [&](glm::vec3 lo, glm::vec3 hi) {
        if (hi.x > lo.x && hi.y > lo.y && hi.z > lo.z) {
            (void)tw.world.add(ConvexPolyhedron::from_aabb({lo, hi}));
        }
    };
    add({-400, -1600, -16}, {3600, 1600, 0}); // floor
    for (int w = 0; w < 10; ++w) {
        const float x0 = 150.0f + 330.0f * static_cast<float>(w) + 60.0f * unit(rng);
        const float x1 = x0 + 8.0f + 16.0f * unit(rng);
        // Cut the wall along y into pieces separated by slits.
        float y = -1500.0f;
        while (y < 1500.0f) {
            const float piece = 100.0f + 500.0f * unit(rng);
            const float y1 = std::min(1500.0f, y + piece);
            if (unit(rng) < 0.3f) {
                // A window: the piece has a gap between two heights.
                const float z0 = 40.0f + 100.0f * unit(rng);
                const float z1 = z0 + 2.0f + 46.0f * unit(rng);
                add({x0, y, 0.0f}, {x1, y1, z0});
                add({x0, y, z1}, {x1, y1, 400.0f});
            } else {
                add({x0, y, 0.0f}, {x1, y1, 400.0f});
            }
            y = y1 + 2.0f + 46.0f * unit(rng);
        }
    }
    tw.play_area = Aabb{{-300, -1500, 0}, {3500, 1500, 400}};
    return tw;
}

struct Tally {
    int configs = 0;
    int reference_visible = 0;
    int reference_hidden = 0;
    int culled = 0;
    int misses = 0;
    int parallax = 0;       ///< seen from some eye of the region but not from its centre
    int point_culled = 0;   ///< h = 0 only: the point buffer's culls
    int region0_culled = 0; ///< h = 0 only: the region buffer's culls

    Tally& operator+=(const Tally& t) {
        configs += t.configs;
        reference_visible += t.reference_visible;
        reference_hidden += t.reference_hidden;
        culled += t.culled;
        misses += t.misses;
        parallax += t.parallax;
        point_culled += t.point_culled;
        region0_culled += t.region0_culled;
        return *this;
    }
};

struct PropertyCase {
    const char* name;
    const TestWorld* world;
    std::uint32_t seed;
    int regions;
    int boxes;
};

void run_property(const PropertyCase& pc, const RegionOcclusionBufferConfig& config, Tally& total,
                  bool compare_point) {
    const TestWorld& tw = *pc.world;
    BspTree bsp;
    bsp.build(tw.world);
    RegionOcclusionBuffer buffer(config);
    OcclusionBuffer point;
    testing::WorldDice dice(tw.play_area, pc.seed);
    std::vector<glm::vec3> eyes, targets;
    Tally t;
    for (int r = 0; r < pc.regions; ++r) {
        // Region: the reach box of a player (48, 48, 40), a wider one, a small one, or
        // a point; centred at a random point or next to an occluder vertex.
        glm::vec3 centre = dice.point();
        if (r % 2 == 1) {
            const auto& o =
                tw.world.occluder(static_cast<OccluderId>(dice.rng() % tw.world.size()));
            const glm::vec3 v = o.vertices()[dice.rng() % o.vertices().size()];
            centre = v + (v - o.bounding_sphere().center) * (0.05f + 0.5f * dice.unit());
        }
        glm::vec3 half(48.0f, 48.0f, 40.0f);
        const int kind = r % 5;
        if (kind == 1) {
            half = glm::vec3(100.0f, 100.0f, 60.0f);
        } else if (kind == 2) {
            half = glm::vec3(8.0f + 24.0f * dice.unit(), 8.0f + 24.0f * dice.unit(), 16.0f);
        } else if (kind == 3) {
            half = glm::vec3(4.0f, 4.0f, 64.0f); // a thin, tall region
        }
        if (compare_point) {
            half = glm::vec3(0.0f);
        }
        const Aabb region = Aabb::from_center_half_extents(centre, half);
        buffer.build(region, tw.world, bsp);
        if (compare_point) {
            point.build(centre, tw.world, bsp);
        }
        region_samples(region, compare_point ? 0 : 8, dice.rng, eyes);
        if (compare_point) {
            eyes.assign(1, centre);
        }
        for (int b = 0; b < pc.boxes; ++b) {
            Aabb box =
                testing::random_test_box(dice, tw.world, b, {1.0f, 4.0f, 36.0f, 64.0f, 96.0f});
            if (b % 5 == 0) {
                // Snap a face onto a plane of the region (slab boundaries).
                const int axis = static_cast<int>(dice.rng() % 3);
                const float shift =
                    (dice.unit() < 0.5f ? region.max[axis] : region.min[axis]) - box.min[axis];
                box.min[axis] += shift;
                box.max[axis] += shift;
            }
            const Visibility answer = buffer.test_box(box);
            ++t.configs;
            t.culled += answer == Visibility::occluded;
            if (compare_point) {
                t.region0_culled += answer == Visibility::occluded;
                t.point_culled += point.test_box(box) == Visibility::occluded;
            }
            // Reference: visible when any eye sample sees any box sample.
            Aabb span = box;
            span.extend(region);
            const LocalReference reference(tw.world, span);
            targets.clear();
            ReferenceVisibility::box_samples(box, 3, targets);
            bool seen = false;
            for (const glm::vec3& eye : eyes) {
                if (box.contains(eye)) {
                    seen = true;
                }
                for (std::size_t i = 0; !seen && i < targets.size(); ++i) {
                    seen = !reference.blocked(eye, targets[i]);
                }
                if (seen) {
                    if (answer == Visibility::occluded) {
                        ++t.misses;
                        ADD_FAILURE() << pc.name << ": culled a box seen from the region; region "
                                      << testing::text(region) << " eye " << testing::text(eye)
                                      << " box " << testing::text(box);
                    }
                    break;
                }
            }
            if (seen && !compare_point) {
                // Parallax cases: seen from the region, but not from its centre.
                const glm::vec3 centre_eye = region.center();
                bool centre_seen = box.contains(centre_eye);
                for (std::size_t i = 0; !centre_seen && i < targets.size(); ++i) {
                    centre_seen = !reference.blocked(centre_eye, targets[i]);
                }
                t.parallax += centre_seen ? 0 : 1;
            }
            t.reference_visible += seen ? 1 : 0;
            t.reference_hidden += seen ? 0 : 1;
        }
    }
    std::printf("[ region   ] %-9s %5d configs, %zu eyes/region: reference hidden %5d, "
                "culled %5d (%.1f%% of hidden), misses %d; hidden from the centre only %d\n",
                pc.name, t.configs, eyes.size(), t.reference_hidden, t.culled,
                100.0 * t.culled / std::max(1, t.reference_hidden), t.misses, t.parallax);
    total += t;
}

TEST(RegionOcclusionBufferProperty, NeverCullsWhatAnyEyeOfTheRegionSees) {
    const TestWorld random = make_random_world(31, 150, 2048.0f);
    const TestWorld walls = make_walls_world(32, 60, 3000.0f);
    const TestWorld corridor = make_corridor_world(33, 4, 4);
    const TestWorld city = make_city_world(34, 4, 4);
    const TestWorld slots = make_slotted_walls(35);
    const PropertyCase cases[] = {{"random", &random, 301, 50, 40},
                                  {"walls", &walls, 302, 50, 40},
                                  {"corridor", &corridor, 303, 50, 40},
                                  {"city", &city, 304, 50, 40},
                                  {"slots", &slots, 305, 50, 40}};
    Tally total;
    for (const PropertyCase& pc : cases) {
        run_property(pc, {}, total, false);
    }
    std::printf("[ region   ] total     %5d configs: reference hidden %5d, culled %5d "
                "(%.1f%% of hidden), misses %d\n",
                total.configs, total.reference_hidden, total.culled,
                100.0 * total.culled / std::max(1, total.reference_hidden), total.misses);
    EXPECT_GE(total.configs, 10000);
    // The case point buffers get wrong must be well represented.
    EXPECT_GE(total.parallax, 200);
    EXPECT_EQ(total.misses, 0);
    EXPECT_GT(total.reference_hidden, total.configs / 5);
    EXPECT_GT(total.reference_visible, total.configs / 5);
    // Measured 61% with the defaults; 256 instead of 1024 for D gives 23%.
    EXPECT_GE(total.culled, total.reference_hidden * 50 / 100);
}

TEST(RegionOcclusionBufferProperty, OtherResolutionsAndDistancesAreConservativeToo) {
    const TestWorld walls = make_walls_world(52, 60, 3000.0f);
    const TestWorld corridor = make_corridor_world(53, 4, 4);
    const TestWorld city = make_city_world(54, 3, 3);
    const PropertyCase cases[] = {{"walls", &walls, 502, 8, 25},
                                  {"corridor", &corridor, 503, 8, 25},
                                  {"city", &city, 504, 8, 25}};
    const std::pair<int, float> settings[] = {
        {8, 1024.0f}, {32, 256.0f}, {128, 512.0f}, {64, 64.0f}, {64, 4096.0f}};
    for (const auto& [resolution, distance] : settings) {
        RegionOcclusionBufferConfig config;
        config.face_resolution = resolution;
        config.projection_distance = distance;
        Tally total;
        for (const PropertyCase& pc : cases) {
            run_property(pc, config, total, false);
        }
        std::printf("[ region   ] N = %d, D = %.0f: %d configs, culled %.1f%% of hidden\n",
                    resolution, distance, total.configs,
                    100.0 * total.culled / std::max(1, total.reference_hidden));
        EXPECT_EQ(total.misses, 0) << "N " << resolution << " D " << distance;
        EXPECT_GT(total.culled, 0) << "N " << resolution << " D " << distance;
    }
}

TEST(RegionOcclusionBufferProperty, PointRegionCullsLikeThePointBuffer) {
    const TestWorld random = make_random_world(41, 150, 2048.0f);
    const TestWorld corridor = make_corridor_world(43, 4, 4);
    const TestWorld city = make_city_world(44, 4, 4);
    const PropertyCase cases[] = {{"random-0", &random, 401, 20, 50},
                                  {"corridor-0", &corridor, 403, 20, 50},
                                  {"city-0", &city, 404, 20, 50}};
    Tally total;
    for (const PropertyCase& pc : cases) {
        run_property(pc, {}, total, true);
    }
    std::printf("[ region   ] h = 0: %d configs, reference hidden %d; region buffer culls %d, "
                "point buffer culls %d\n",
                total.configs, total.reference_hidden, total.region0_culled, total.point_culled);
    EXPECT_EQ(total.misses, 0);
    EXPECT_GE(total.region0_culled * 100, total.point_culled * 70);
}

} // namespace
} // namespace dsoc::visibility
