// The map's own PVS: point -> leaf -> cluster, and cluster visibility. Checked for
// conservativeness against rays: two spawn points whose eyes see each other past
// every occluder must be in clusters the PVS calls visible.

#include "dsoc/maps/pk3.hpp"
#include "dsoc/maps/q3_map.hpp"
#include "dsoc/maps/q3_pvs.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

namespace dsoc::maps {
namespace {

/// Does the segment a-b pass through the interior of the convex solid?
bool segment_hits(const visibility::ConvexPolyhedron& solid, glm::vec3 a, glm::vec3 b) {
    float enter = 0.0f;
    float leave = 1.0f;
    for (const visibility::Plane& plane : solid.planes()) {
        const float da = plane.signed_distance(a);
        const float db = plane.signed_distance(b);
        if (da >= 0.0f && db >= 0.0f) {
            return false;
        }
        if (da < 0.0f && db < 0.0f) {
            continue;
        }
        const float t = da / (da - db);
        if (da >= 0.0f) {
            enter = std::max(enter, t);
        } else {
            leave = std::min(leave, t);
        }
        if (enter >= leave) {
            return false;
        }
    }
    return leave - enter > 1e-4f;
}

q3::Q3Bsp load_bsp(const std::string& name) {
    auto bytes = read_pk3_entry(test::kOpenArenaPak, "maps/" + name + ".bsp");
    EXPECT_TRUE(bytes.ok());
    auto bsp = q3::parse_q3_bsp(bytes.value(), name);
    EXPECT_TRUE(bsp.ok());
    return std::move(bsp).value();
}

TEST(Q3Pvs, SpawnClustersSeeThemselvesAndRaysAgree) {
    DSOC_REQUIRE_OPENARENA();
    for (const char* name : {"oa_dm4", "q3dm6ish", "oa_dm1", "ctf_inyard"}) {
        const q3::Q3Bsp bsp = load_bsp(name);
        ASSERT_TRUE(q3::has_visibility(bsp)) << name;
        const auto map = map_from_q3_bsp(bsp, name);
        ASSERT_TRUE(map.ok());
        std::vector<glm::vec3> eyes;
        for (const SpawnPoint& spawn : map->spawn_points) {
            const glm::vec3 eye = spawn.origin + glm::vec3(0, 0, 26);
            const int cluster = q3::cluster_at(bsp, eye);
            EXPECT_GE(cluster, 0) << name << ": spawn eye in solid or outside";
            EXPECT_TRUE(q3::cluster_visible(bsp, cluster, cluster)) << name;
            eyes.push_back(eye);
        }
        std::size_t ray_visible = 0;
        std::size_t pvs_rejected = 0;
        for (std::size_t i = 0; i < eyes.size(); ++i) {
            for (std::size_t j = 0; j < eyes.size(); ++j) {
                const bool pvs = q3::cluster_visible(bsp, q3::cluster_at(bsp, eyes[i]),
                                                     q3::cluster_at(bsp, eyes[j]));
                pvs_rejected += pvs ? 0 : 1;
                bool blocked = false;
                for (const auto& occluder : map->occluders) {
                    if (segment_hits(occluder, eyes[i], eyes[j])) {
                        blocked = true;
                        break;
                    }
                }
                if (!blocked) {
                    ++ray_visible;
                    EXPECT_TRUE(pvs) << name << ": spawns " << i << " and " << j
                                     << " see each other but the PVS says no";
                }
            }
        }
        EXPECT_GT(ray_visible, eyes.size()) << name; // some pairs besides i == j
        EXPECT_GT(pvs_rejected, 0u) << name;         // and the PVS does cull something
    }
}

TEST(Q3Pvs, InsideSolidIsClusterMinusOne) {
    DSOC_REQUIRE_OPENARENA();
    const q3::Q3Bsp bsp = load_bsp("oa_dm4");
    const auto map = map_from_q3_bsp(bsp, "oa_dm4");
    ASSERT_TRUE(map.ok());
    std::size_t solid = 0;
    std::size_t tested = 0;
    for (const auto& occluder : map->occluders) {
        const glm::vec3 size = occluder.bounds().size();
        if (std::min({size.x, size.y, size.z}) < 16.0f) {
            continue; // thin brushes: the centre may sit on a leaf boundary
        }
        ++tested;
        solid += q3::cluster_at(bsp, occluder.bounds().center()) < 0 ? 1 : 0;
    }
    ASSERT_GT(tested, 20u);
    EXPECT_GT(solid, tested * 9 / 10);
}

TEST(Q3Pvs, NoVisDataMeansEverythingVisible) {
    DSOC_REQUIRE_OPENARENA();
    const q3::Q3Bsp bsp = load_bsp("oa_ctf2");
    EXPECT_FALSE(q3::has_visibility(bsp));
    EXPECT_TRUE(q3::cluster_visible(bsp, 0, 5));
    EXPECT_TRUE(q3::cluster_visible(bsp, -1, 3));
}

TEST(Q3Pvs, EmptyMapHasNoLeaf) {
    const auto bsp = q3::parse_q3_bsp(test::small_map_writer().build(), "small");
    ASSERT_TRUE(bsp.ok());
    EXPECT_EQ(q3::find_leaf(bsp.value(), {0, 0, 0}), -1);
    EXPECT_EQ(q3::cluster_at(bsp.value(), {0, 0, 0}), -1);
}

} // namespace
} // namespace dsoc::maps

namespace dsoc::maps {
namespace {

TEST(Q3Pvs, SmallTreeFindsLeafsAndReadsRows) {
    test::BspWriter w = test::small_map_writer();
    // Node 0 splits on plane 0 (x = 256, normal +x): front (x >= 256) is leaf 0,
    // back is node 1, which splits on plane 2 (y = 256): front leaf 1, back leaf 2.
    w.put_i32s(q3::Lump::nodes, {0, -1, 1, 0, 0, 0, 0, 0, 0});
    w.put_i32s(q3::Lump::nodes, {2, -2, -3, 0, 0, 0, 0, 0, 0});
    w.put_i32s(q3::Lump::leafs, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
    w.put_i32s(q3::Lump::leafs, {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
    w.put_i32s(q3::Lump::leafs, {-1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
    // Two clusters, one byte a row: cluster 0 sees only itself, cluster 1 sees both.
    w.put_i32s(q3::Lump::visibility, {2, 1});
    w.put(q3::Lump::visibility, std::uint8_t{0x01});
    w.put(q3::Lump::visibility, std::uint8_t{0x03});
    const auto bsp = q3::parse_q3_bsp(w.build(), "tree");
    ASSERT_TRUE(bsp.ok()) << bsp.error().message();
    EXPECT_EQ(q3::find_leaf(bsp.value(), {300, 0, 0}), 0);
    EXPECT_EQ(q3::find_leaf(bsp.value(), {0, 300, 0}), 1);
    EXPECT_EQ(q3::find_leaf(bsp.value(), {0, 0, 0}), 2);
    EXPECT_EQ(q3::cluster_at(bsp.value(), {300, 0, 0}), 0);
    EXPECT_EQ(q3::cluster_at(bsp.value(), {0, 0, 0}), -1);
    EXPECT_TRUE(q3::cluster_visible(bsp.value(), 0, 0));
    EXPECT_FALSE(q3::cluster_visible(bsp.value(), 0, 1));
    EXPECT_TRUE(q3::cluster_visible(bsp.value(), 1, 0));
    EXPECT_TRUE(q3::cluster_visible(bsp.value(), 1, 1));
    EXPECT_TRUE(q3::cluster_visible(bsp.value(), -1, 1)); // no answer: visible
    EXPECT_TRUE(q3::cluster_visible(bsp.value(), 0, 7));  // out of range: visible
}

} // namespace
} // namespace dsoc::maps
