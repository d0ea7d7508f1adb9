#include "dsoc/visibility/loose_octree.hpp"
#include "dsoc/visibility/seeds/occlusion_buffer.hpp"

#include "test_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <vector>

namespace dsoc::visibility {
namespace {

struct Fixture {
    std::mt19937 rng{5};
    std::uniform_real_distribution<float> unit{0.0f, 1.0f};
    Aabb random_box(float extent = 4000.0f) {
        const glm::vec3 c(unit(rng) * extent - extent * 0.5f, unit(rng) * extent - extent * 0.5f,
                          unit(rng) * extent - extent * 0.5f);
        const float h = unit(rng) < 0.8f ? 4.0f + 32.0f * unit(rng) : 100.0f + 900.0f * unit(rng);
        return Aabb::from_center_half_extents(c, glm::vec3(h, h * 0.7f, h * 1.3f));
    }
};

/// subtree_items equals the items actually stored below, every item's box lies in its
/// node's loose bounds (except at the root), and every non-root node has content.
void expect_invariants(const LooseOctree& tree) {
    std::size_t total = 0;
    std::function<std::uint32_t(std::int32_t)> count = [&](std::int32_t index) -> std::uint32_t {
        const OctreeNode& n = tree.node(index);
        std::uint32_t here = 0;
        for (ItemId id = 0; id < tree.config().max_items; ++id) {
            if (tree.contains(id) && tree.node_of(id) == index) {
                ++here;
                if (index != tree.root()) {
                    EXPECT_TRUE(n.loose_bounds.contains(tree.bounds_of(id)));
                }
            }
        }
        for (std::int32_t c : n.children) {
            if (c >= 0) {
                EXPECT_EQ(tree.node(c).parent, index);
                EXPECT_TRUE(tree.node(c).has_dynamic_content());
                here += count(c);
            }
        }
        EXPECT_EQ(n.subtree_items, here);
        return here;
    };
    total = count(tree.root());
    EXPECT_EQ(total, tree.size());
}

TEST(LooseOctree, InsertRemoveAndQueriesMatchBruteForce) {
    Fixture fx;
    LooseOctreeConfig config;
    config.max_items = 300;
    LooseOctree tree(config);
    std::map<ItemId, Aabb> truth;
    for (ItemId id = 0; id < 300; ++id) {
        // Some items lie outside the world bounds on purpose.
        const Aabb b = fx.random_box(id % 10 == 0 ? 20000.0f : 7000.0f);
        ASSERT_TRUE(tree.insert(id, b));
        truth[id] = b;
    }
    EXPECT_FALSE(tree.insert(5, fx.random_box()));   // already present
    EXPECT_FALSE(tree.insert(300, fx.random_box())); // out of range
    EXPECT_FALSE(tree.insert(299, Aabb::empty()));   // (present anyway) invalid
    for (ItemId id = 0; id < 300; id += 3) {
        ASSERT_TRUE(tree.remove(id));
        truth.erase(id);
    }
    EXPECT_FALSE(tree.remove(0));
    expect_invariants(tree);
    for (int q = 0; q < 50; ++q) {
        const Aabb query = fx.random_box(6000.0f).expanded(200.0f);
        std::set<ItemId> got, expected;
        tree.query_box(query, [&](ItemId id) { got.insert(id); });
        for (const auto& [id, b] : truth) {
            if (b.overlaps(query)) {
                expected.insert(id);
            }
        }
        EXPECT_EQ(got, expected);
        const Sphere sphere{query.center(), 500.0f};
        got.clear();
        expected.clear();
        tree.query_sphere(sphere, [&](ItemId id) { got.insert(id); });
        for (const auto& [id, b] : truth) {
            if (overlaps(sphere, b)) {
                expected.insert(id);
            }
        }
        EXPECT_EQ(got, expected);
    }
    // Frustum query: conservative superset of the items inside.
    const Frustum frustum =
        Frustum::perspective(glm::vec3(0.0f), {1, 0, 0}, {0, 0, 1}, 1.2f, 1.5f, 1.0f, 3000.0f);
    std::set<ItemId> got;
    tree.query_frustum(frustum, [&](ItemId id) { got.insert(id); });
    for (const auto& [id, b] : truth) {
        EXPECT_EQ(got.count(id) == 1, frustum.may_overlap(b)) << id;
    }
}

TEST(LooseOctree, TakesIdsInAnyOrderUpToMaxItems) {
    // Storage grows with the largest id inserted: doubling (7, then 70), then straight
    // to the limit (4999), then a lower id again.
    Fixture fx;
    LooseOctreeConfig config;
    config.max_items = 5000;
    LooseOctree tree(config);
    EXPECT_FALSE(tree.contains(4999));
    ASSERT_TRUE(tree.insert(7, fx.random_box()));
    ASSERT_TRUE(tree.insert(70, fx.random_box()));
    ASSERT_TRUE(tree.insert(4999, fx.random_box()));
    ASSERT_TRUE(tree.insert(4000, fx.random_box()));
    EXPECT_FALSE(tree.insert(5000, fx.random_box())); // out of range
    EXPECT_FALSE(tree.contains(5000));
    EXPECT_FALSE(tree.contains(8));
    EXPECT_TRUE(tree.contains(4999) && tree.contains(7) && tree.contains(70) &&
                tree.contains(4000));
    EXPECT_EQ(tree.size(), 4u);
    ASSERT_TRUE(tree.remove(4999));
    EXPECT_FALSE(tree.remove(4999));
    expect_invariants(tree);
}

TEST(LooseOctree, MovesTouchOnlyTheCommonAncestorSubtree) {
    Fixture fx;
    LooseOctreeConfig config;
    config.max_items = 200;
    LooseOctree tree(config);
    for (ItemId id = 0; id < 200; ++id) {
        ASSERT_TRUE(tree.insert(id, fx.random_box()));
    }
    int deep_moves = 0;
    for (int step = 0; step < 2000; ++step) {
        const ItemId id = static_cast<ItemId>(fx.rng() % 200);
        // Mostly small steps (a player moving), sometimes a teleport.
        Aabb next = tree.bounds_of(id);
        const float reach = step % 10 == 0 ? 3000.0f : 40.0f;
        const glm::vec3 delta((fx.unit(fx.rng) - 0.5f) * reach, (fx.unit(fx.rng) - 0.5f) * reach,
                              (fx.unit(fx.rng) - 0.5f) * reach);
        next = {next.min + delta, next.max + delta};
        // Snapshot every live node's count and the old path.
        std::map<std::int32_t, std::uint32_t> before;
        std::vector<std::int32_t> stack{tree.root()};
        while (!stack.empty()) {
            const std::int32_t n = stack.back();
            stack.pop_back();
            before[n] = tree.node(n).subtree_items;
            for (std::int32_t c : tree.node(n).children) {
                if (c >= 0) {
                    stack.push_back(c);
                }
            }
        }
        std::vector<std::int32_t> old_path;
        for (std::int32_t n = tree.node_of(id); n >= 0; n = tree.node(n).parent) {
            old_path.push_back(n);
        }
        ASSERT_TRUE(tree.move(id, next));
        const std::int32_t lca = tree.last_update_ancestor();
        // The ancestor lies on both the old and the new path.
        EXPECT_NE(std::find(old_path.begin(), old_path.end(), lca), old_path.end());
        bool on_new_path = false;
        for (std::int32_t n = tree.node_of(id); n >= 0; n = tree.node(n).parent) {
            on_new_path = on_new_path || n == lca;
        }
        EXPECT_TRUE(on_new_path);
        deep_moves += tree.node(lca).depth > 0 ? 1 : 0;
        // Every touched node is the ancestor or below it.
        for (std::int32_t t : tree.last_update_touched()) {
            std::int32_t n = t;
            while (n >= 0 && n != lca) {
                n = tree.node(n).parent;
            }
            EXPECT_EQ(n, lca) << "touched node " << t << " outside the LCA subtree";
        }
        // Nodes outside the LCA's subtree kept their counts.
        for (const auto& [n, items] : before) {
            std::int32_t up = n;
            while (up >= 0 && up != lca) {
                up = tree.node(up).parent;
            }
            if (up != lca) {
                EXPECT_EQ(tree.node(n).subtree_items, items);
            }
        }
    }
    EXPECT_GT(deep_moves, 500) << "most small moves should stay below the root";
    expect_invariants(tree);
    // Removing everything returns every node but the root to the pool.
    for (ItemId id = 0; id < 200; ++id) {
        ASSERT_TRUE(tree.remove(id));
    }
    EXPECT_EQ(tree.live_nodes(), 1u);
    EXPECT_FALSE(tree.node(tree.root()).has_dynamic_content());
}

TEST(LooseOctree, FrontToBackTraversalCullsBehindAWall) {
    testing::Scene wall;
    wall.add_box({100, -2000, -2000}, {120, 2000, 2000});
    wall.build();
    OcclusionBuffer buffer;
    buffer.build(glm::vec3(0.0f), wall.world, wall.bsp);
    Fixture fx;
    LooseOctreeConfig config;
    config.max_items = 500;
    LooseOctree tree(config);
    for (ItemId id = 0; id < 500; ++id) {
        ASSERT_TRUE(tree.insert(id, fx.random_box(3000.0f)));
    }
    std::set<ItemId> reported;
    const int culled = tree.traverse_front_to_back(glm::vec3(0.0f), buffer,
                                                   [&](ItemId id) { reported.insert(id); });
    std::set<ItemId> expected;
    for (ItemId id = 0; id < 500; ++id) {
        if (buffer.test_box(tree.bounds_of(id)) == Visibility::visible) {
            expected.insert(id);
        }
    }
    EXPECT_EQ(reported, expected);
    EXPECT_LT(expected.size(), 450u);
    EXPECT_GT(culled, 0);
}

} // namespace
} // namespace dsoc::visibility
