#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <random>
#include <vector>

namespace dsoc::visibility {
namespace {

bool sphere_contains(const Sphere& outer, const Sphere& inner) {
    return glm::length(inner.center - outer.center) + inner.radius <=
           outer.radius * 1.0001f + 1e-3f;
}

TEST(BspTree, EveryOccluderOnceAndVolumesContainChildren) {
    const TestWorld tw = make_random_world(7, 500, 4096.0f);
    BspTree bsp;
    bsp.build(tw.world);
    ASSERT_FALSE(bsp.empty());
    EXPECT_EQ(bsp.nodes().size(), 2 * tw.world.size() - 1);
    for (const BspNode& node : bsp.nodes()) {
        if (node.is_leaf()) {
            EXPECT_TRUE(
                sphere_contains(node.sphere, tw.world.occluder(node.occluder).bounding_sphere()));
            continue;
        }
        for (int c = 0; c < 2; ++c) {
            const BspNode& child = bsp.nodes()[static_cast<std::size_t>(node.children[c])];
            EXPECT_TRUE(sphere_contains(node.sphere, child.sphere));
            EXPECT_TRUE(node.bounds.contains(child.bounds));
        }
    }
    std::vector<int> seen(tw.world.size(), 0);
    bsp.traverse_near_to_far(
        glm::vec3(100.0f), [](const BspNode&) { return true; },
        [&](OccluderId id) {
            ++seen[id];
            return true;
        });
    for (int s : seen) {
        EXPECT_EQ(s, 1);
    }
    // Logarithmic-ish depth.
    EXPECT_LT(bsp.depth(), 64);
}

TEST(BspTree, SingleAndEmptyWorlds) {
    OccluderWorld empty_world;
    BspTree bsp;
    bsp.build(empty_world);
    EXPECT_TRUE(bsp.empty());
    std::vector<OccluderId> out{1, 2};
    bsp.near_to_far(glm::vec3(0.0f), 1e9f, 100, out);
    EXPECT_TRUE(out.empty());
    OccluderWorld one;
    (void)one.add(ConvexPolyhedron::from_aabb({{0, 0, 0}, {1, 1, 1}}));
    bsp.build(one);
    bsp.near_to_far(glm::vec3(5.0f), 1e9f, 100, out);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0], 0u);
}

/// For disjoint occluders laid out with gaps, the traversal is a visibility order:
/// if B hides part of A from the eye, B comes first.
TEST(BspTree, NearToFarIsAVisibilityOrderForDisjointOccluders) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    OccluderWorld world;
    constexpr float kCell = 100.0f;
    for (int x = 0; x < 8; ++x) {
        for (int y = 0; y < 8; ++y) {
            for (int z = 0; z < 3; ++z) {
                if (unit(rng) < 0.3f) {
                    continue;
                }
                const glm::vec3 lo = glm::vec3(x, y, z) * kCell +
                                     glm::vec3(unit(rng), unit(rng), unit(rng)) * 30.0f + 5.0f;
                const glm::vec3 size = glm::vec3(unit(rng), unit(rng), unit(rng)) * 55.0f + 5.0f;
                (void)world.add(ConvexPolyhedron::from_aabb({lo, lo + size}));
            }
        }
    }
    BspTree bsp;
    bsp.build(world);
    int separated = 0;
    int inner = 0;
    for (const BspNode& n : bsp.nodes()) {
        if (!n.is_leaf()) {
            ++inner;
            separated += n.separated ? 1 : 0;
        }
    }
    // Most splits are exact; the order is only promised below exact splits.
    EXPECT_GE(separated * 10, inner * 9) << separated << " of " << inner;
    std::vector<int> parent(bsp.nodes().size(), -1);
    std::vector<int> leaf_of(world.size(), -1);
    for (std::size_t i = 0; i < bsp.nodes().size(); ++i) {
        const BspNode& n = bsp.nodes()[i];
        if (n.is_leaf()) {
            leaf_of[n.occluder] = static_cast<int>(i);
        } else {
            parent[static_cast<std::size_t>(n.children[0])] = static_cast<int>(i);
            parent[static_cast<std::size_t>(n.children[1])] = static_cast<int>(i);
        }
    }
    auto lca_separated = [&](OccluderId a, OccluderId b) {
        std::vector<int> up;
        for (int n = leaf_of[a]; n >= 0; n = parent[static_cast<std::size_t>(n)]) {
            up.push_back(n);
        }
        for (int n = leaf_of[b]; n >= 0; n = parent[static_cast<std::size_t>(n)]) {
            if (std::find(up.begin(), up.end(), n) != up.end()) {
                return bsp.nodes()[static_cast<std::size_t>(n)].separated;
            }
        }
        return false;
    };
    std::vector<OccluderId> order;
    std::vector<int> rank(world.size());
    int violations = 0;
    int checked = 0;
    for (int trial = 0; trial < 40; ++trial) {
        const glm::vec3 eye = glm::vec3(unit(rng) * 800.0f, unit(rng) * 800.0f, unit(rng) * 300.0f);
        bool inside = false;
        for (const auto& o : world.occluders()) {
            inside = inside || o.contains(eye);
        }
        if (inside) {
            continue;
        }
        bsp.near_to_far(eye, 1e9f, world.size(), order);
        ASSERT_EQ(order.size(), world.size());
        for (std::size_t i = 0; i < order.size(); ++i) {
            rank[order[i]] = static_cast<int>(i);
        }
        for (OccluderId a = 0; a < world.size(); ++a) {
            const glm::vec3 target = world.occluder(a).bounds().center();
            for (OccluderId b = 0; b < world.size(); ++b) {
                if (a == b) {
                    continue;
                }
                if (lca_separated(a, b) && segment_blocked_by(eye, target, world.face_planes(b))) {
                    ++checked;
                    violations += rank[b] > rank[a] ? 1 : 0;
                }
            }
        }
    }
    EXPECT_GT(checked, 100);
    EXPECT_EQ(violations, 0);
}

TEST(BspTree, DistanceAndCountBudget) {
    const TestWorld tw = make_corridor_world(3, 6, 6);
    BspTree bsp;
    bsp.build(tw.world);
    const glm::vec3 eye(256.0f, 256.0f, 64.0f);
    std::vector<OccluderId> out;
    bsp.near_to_far(eye, 600.0f, 1000000, out);
    ASSERT_FALSE(out.empty());
    EXPECT_LT(out.size(), tw.world.size());
    for (OccluderId id : out) {
        EXPECT_LE(distance_squared(tw.world.occluder(id).bounds(), eye), 600.0f * 600.0f);
    }
    std::size_t within = 0;
    for (OccluderId id = 0; id < tw.world.size(); ++id) {
        within += distance_squared(tw.world.occluder(id).bounds(), eye) <= 600.0f * 600.0f;
    }
    EXPECT_EQ(out.size(), within);
    bsp.near_to_far(eye, 1e9f, 10, out);
    EXPECT_EQ(out.size(), 10u);
}

} // namespace
} // namespace dsoc::visibility

namespace dsoc::visibility {
namespace {

/// Best-first over node bounds: a parent's box contains its children's, so its
/// distance is a lower bound and leaves come out sorted by their own distance.
TEST(BspTree, NearestFirstYieldsOccludersByIncreasingDistance) {
    const TestWorld tw = make_random_world(17, 800, 4096.0f);
    BspTree bsp;
    bsp.build(tw.world);
    std::vector<std::pair<float, std::int32_t>> heap;
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> unit(0.0f, 4096.0f);
    for (int trial = 0; trial < 10; ++trial) {
        const glm::vec3 eye(unit(rng), unit(rng), unit(rng));
        float last = -1.0f;
        std::size_t count = 0;
        bool sorted = true;
        bsp.traverse_nearest_first(
            eye, heap, [](const BspNode&) { return true; },
            [&](OccluderId id) {
                const float d = distance_squared(tw.world.occluder(id).bounds(), eye);
                sorted = sorted && d >= last;
                last = d;
                ++count;
                return true;
            });
        EXPECT_TRUE(sorted);
        EXPECT_EQ(count, tw.world.size());
    }
}

} // namespace
} // namespace dsoc::visibility
