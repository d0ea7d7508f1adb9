// The PVS stage never rejects a box that an eye of the region sees (brute-force rays),
// on real maps with wandering bots; and it does reject something.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/pvs_region_visibility.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "test_support.hpp"

#include "dsoc/maps/q3_map.hpp"
#include "dsoc/maps/q3_pvs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <random>

namespace dsoc::maps {
namespace {

/// A culler that never proves anything: isolates the PVS stage.
class NothingHidden final : public visibility::RegionVisibility {
public:
    void build(const visibility::Aabb&) override {}
    [[nodiscard]] visibility::Visibility test_box(const visibility::Aabb&) const override {
        return visibility::Visibility::visible;
    }
};

class PvsStageOnMaps : public ::testing::TestWithParam<const char*> {};

TEST_P(PvsStageOnMaps, NeverRejectsWhatAnEyeOfTheRegionSees) {
    DSOC_REQUIRE_OPENARENA();
    auto loaded = load_map(GetParam(), MapSearch::from_environment());
    ASSERT_TRUE(loaded) << loaded.error().message();
    const Map& map = loaded.value();
    ASSERT_NE(map.pvs, nullptr);
    ASSERT_TRUE(map.pvs->has_visibility());
    visibility::OccluderWorld world;
    for (const auto& o : map.occluders) {
        world.add(o);
    }
    const visibility::ReferenceVisibility ref(world);
    const sim::MoveConfig move;
    const sim::CollisionWorld collision(map.collision_brushes);
    auto bots = sim::spawn_wander_bots(collision, move, map.spawn_points, 60, 9);
    const sim::WanderConfig wander;
    for (int t = 0; t < 150; ++t) {
        for (auto& b : bots) {
            sim::wander_step(b, collision, wander, move, map.spawn_points, map.hazards, 1.0f / 30);
        }
    }
    PvsRegionVisibility stage(map.pvs, std::make_unique<NothingHidden>());
    int rejected = 0;
    int checked = 0;
    for (std::size_t v = 0; v < 20; ++v) {
        const glm::vec3 eye = bots[v].state.position + glm::vec3(0, 0, move.eye_height);
        const visibility::Aabb region{eye - glm::vec3(53, 53, 29), eye + glm::vec3(53, 53, 116)};
        stage.build(region);
        for (std::size_t b = 20; b < bots.size(); ++b) {
            const visibility::Aabb box{bots[b].state.position + move.mins,
                                       bots[b].state.position + move.maxs};
            ++checked;
            // A prepared box (its clusters computed once) gets the same answers, and
            // the coarse test alone is the PVS stage.
            visibility::PreparedBox prepared;
            stage.prepare(box, prepared);
            ASSERT_TRUE(prepared.prepared);
            ASSERT_EQ(stage.test_prepared(prepared), stage.test_box(box));
            ASSERT_EQ(stage.test_prepared_quick(prepared), stage.test_box_quick(box));
            ASSERT_EQ(stage.test_prepared_coarse(prepared), stage.test_box(box));
            if (stage.test_box(box) != visibility::Visibility::occluded) {
                continue;
            }
            ++rejected;
            for (int k = 0; k < 28; ++k) { // a 3x3x3 lattice, then the eye itself
                const glm::vec3 f(k % 3, (k / 3) % 3, k / 9);
                const glm::vec3 e = k == 27 ? eye : region.min + region.size() * f * 0.5f;
                ASSERT_EQ(ref.test_box(e, box, 3), visibility::Visibility::occluded)
                    << GetParam() << ": viewer " << v << " bot " << b << " seen from eye " << k;
            }
        }
    }
    EXPECT_GT(rejected, 0) << "the PVS stage should reject something on " << GetParam();
    std::printf("%s: PVS stage rejected %d of %d boxes for the whole eye region\n", GetParam(),
                rejected, checked);
}

INSTANTIATE_TEST_SUITE_P(Maps, PvsStageOnMaps, ::testing::Values("oa_dm4", "q3dm6ish", "oa_dm1"));

TEST(Pvs, BoxClustersContainThePointClustersInside) {
    DSOC_REQUIRE_OPENARENA();
    auto bsp = find_q3_bsp("oa_dm4", MapSearch::from_environment());
    ASSERT_TRUE(bsp) << bsp.error().message();
    const Pvs pvs(bsp.value());
    auto loaded = map_from_q3_bsp(bsp.value(), "oa_dm4");
    ASSERT_TRUE(loaded);
    const visibility::Aabb bounds = loaded.value().bounds;
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<std::int32_t> clusters;
    int boxes_with_clusters = 0;
    for (int i = 0; i < 2000; ++i) {
        const glm::vec3 c = bounds.min + bounds.size() * glm::vec3(u(rng), u(rng), u(rng));
        const glm::vec3 h(8.0f + 60.0f * u(rng), 8.0f + 60.0f * u(rng), 8.0f + 60.0f * u(rng));
        const visibility::Aabb box{c - h, c + h};
        pvs.clusters_of(box, clusters);
        boxes_with_clusters += clusters.empty() ? 0 : 1;
        for (int k = 0; k < 27; ++k) {
            const glm::vec3 f(k % 3, (k / 3) % 3, k / 9);
            const glm::vec3 p = box.min + box.size() * f * 0.5f;
            const int cluster = q3::cluster_at(bsp.value(), p);
            if (cluster >= 0) {
                ASSERT_TRUE(std::binary_search(clusters.begin(), clusters.end(), cluster))
                    << "point cluster " << cluster << " missing from the box's clusters";
            }
        }
        // A point's own cluster sees itself.
        const int centre = q3::cluster_at(bsp.value(), c);
        if (centre >= 0) {
            EXPECT_TRUE(pvs.cluster_visible(centre, centre));
        }
    }
    EXPECT_GT(boxes_with_clusters, 500);
}

TEST(Pvs, MapsWithoutVisDataPassEverything) {
    DSOC_REQUIRE_OPENARENA();
    auto loaded = load_map("oa_ctf2", MapSearch::from_environment());
    ASSERT_TRUE(loaded) << loaded.error().message();
    ASSERT_NE(loaded.value().pvs, nullptr);
    EXPECT_FALSE(loaded.value().pvs->has_visibility());
    PvsRegionVisibility stage(loaded.value().pvs, std::make_unique<NothingHidden>());
    stage.build({glm::vec3(0), glm::vec3(10)});
    EXPECT_EQ(stage.test_box({glm::vec3(1000), glm::vec3(1030)}), visibility::Visibility::visible);
}

// oa_dm6's floor grates (alpha-tested in the game's scripts, solid and not translucent in
// the compiled map) are walls to the compiler's vis: its PVS hides what is seen through
// them. Eyes and boxes around each see-through brush, judged by brute-force rays: the
// compiler's bits hide some that are seen (the test has teeth), the opened PVS none.
TEST(PvsThroughSeeThroughBrushes, HidesNothingAGrateLetsBeSeen) {
    DSOC_REQUIRE_OPENARENA();
    const MapSearch search = MapSearch::from_environment();
    auto loaded = load_map("oa_dm6", search);
    ASSERT_TRUE(loaded) << loaded.error().message();
    const Map& map = loaded.value();
    if (map.stats.shader_scripts == 0) {
        GTEST_SKIP() << "OpenArena's shader scripts (Debian openarena-data) are not installed: "
                        "by name alone oa_dm6's grates are not all see-through";
    }
    ASSERT_GT(map.see_through.size(), 20u);
    auto bsp = find_q3_bsp("oa_dm6", search);
    ASSERT_TRUE(bsp) << bsp.error().message();
    const Pvs compiled(bsp.value()); // the compiler's bits, not opened
    const Pvs& opened = *map.pvs;
    EXPECT_GT(opened.opened_pairs(), 0u);
    visibility::OccluderWorld world;
    for (const auto& o : map.occluders) {
        world.add(o);
    }
    const visibility::ReferenceVisibility ref(world);
    std::mt19937 random(6);
    const auto around = [&](const visibility::Aabb& box, float by) {
        std::uniform_real_distribution<float> x(box.min.x - by, box.max.x + by);
        std::uniform_real_distribution<float> y(box.min.y - by, box.max.y + by);
        std::uniform_real_distribution<float> z(box.min.z - by, box.max.z + by);
        return glm::vec3(x(random), y(random), z(random));
    };
    std::vector<std::int32_t> clusters;
    std::vector<std::uint8_t> rows;
    // Whether `pvs` lets the eye's cluster see `box`; nullopt when the eye is in solid.
    const auto pvs_may_see = [&](const Pvs& pvs, glm::vec3 eye,
                                 const visibility::Aabb& box) -> std::optional<bool> {
        if (!pvs.clusters_of({eye - glm::vec3(0.5f), eye + glm::vec3(0.5f)}, clusters)) {
            return std::nullopt;
        }
        pvs.union_of_rows(clusters, rows);
        return pvs.may_see(rows, box, clusters);
    };
    const glm::vec3 half(15.0f, 15.0f, 28.0f);
    int judged = 0;
    int seen_but_compiled_hides = 0;
    for (const visibility::Aabb& grate : map.see_through) {
        for (int e = 0; e < 40; ++e) {
            const glm::vec3 eye = around(grate, 160.0f);
            for (int b = 0; b < 40; ++b) {
                const glm::vec3 centre = around(grate, 600.0f);
                const visibility::Aabb box{centre - half, centre + half};
                const auto compiled_sees = pvs_may_see(compiled, eye, box);
                if (!compiled_sees || *compiled_sees) {
                    continue; // in solid, or the compiler's PVS already lets it be seen
                }
                ++judged;
                if (ref.test_box(eye, box, 3) == visibility::Visibility::occluded) {
                    continue;
                }
                ++seen_but_compiled_hides;
                ASSERT_TRUE(pvs_may_see(opened, eye, box).value_or(true))
                    << "the opened PVS hides a box seen from (" << eye.x << ", " << eye.y << ", "
                    << eye.z << ") at (" << centre.x << ", " << centre.y << ", " << centre.z << ")";
            }
        }
    }
    EXPECT_GT(seen_but_compiled_hides, 0)
        << "no box seen through a grate was found (of " << judged << " the compiler hides)";
    std::printf("oa_dm6: %d boxes the compiler's PVS hides are seen (of %d it hides near %zu "
                "see-through brushes); %llu cluster pairs opened\n",
                seen_but_compiled_hides, judged, map.see_through.size(),
                static_cast<unsigned long long>(opened.opened_pairs()));
}

} // namespace
} // namespace dsoc::maps
