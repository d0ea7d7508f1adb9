#pragma once
// Loose octree for moving items (entities, TBVs), named by integer ids. A node of
// cell size s has loose bounds of size 2s (its cell grown by s/2 on each side); an
// item lives in the deepest node whose loose bounds hold it given its centre's cell.
// A move touches only the subtree under the least common ancestor of the old and new
// nodes (guide: UpdateOctreeForMovement). Nodes are pooled; empty subtrees are
// returned to the pool, so every non-root node has dynamic content.

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace dsoc::visibility {

/// Caller-chosen item id, dense: 0 <= id < LooseOctreeConfig::max_items (e.g. an
/// entity slot). The octree never invents ids.
using ItemId = std::uint32_t;

struct LooseOctreeConfig {
    /// Region the tree subdivides (made a cube around its centre). Items outside it
    /// are still stored (at the root) and found by every query. [Units: world units]
    Aabb world_bounds{glm::vec3(-4096.0f), glm::vec3(4096.0f)};
    /// Depth of the finest cells (root = 0). [Units: levels] [Limit: 0..15]
    int max_depth = 7;
    /// Ids must be below this; storage for them grows with the largest id inserted.
    /// [Units: items] [Limit: >= 1]
    std::uint32_t max_items = 4096;
};

/// One pooled node of a LooseOctree (read access for traversals and tests).
struct OctreeNode {
    Aabb loose_bounds; ///< 2x the cell
    std::array<std::int32_t, 8> children{-1, -1, -1, -1, -1, -1, -1, -1};
    std::int32_t parent = -1;
    std::int32_t first_item = -1;      ///< intrusive item list
    std::uint32_t subtree_items = 0;   ///< items here and below
    std::uint32_t cell[3] = {0, 0, 0}; ///< cell coordinates at `depth`
    std::uint8_t depth = 0;
    [[nodiscard]] bool has_dynamic_content() const { return subtree_items != 0; }
};

/// Not thread-safe to modify; const queries may run concurrently with each other.
class LooseOctree {
public:
    explicit LooseOctree(const LooseOctreeConfig& config = {});

    /// False (and no change) when the id is out of range, already present, or the
    /// box is empty/non-finite.
    bool insert(ItemId id, const Aabb& bounds);
    /// False when the id is not present.
    bool remove(ItemId id);
    /// Moves an item; only nodes under the least common ancestor of its old and new
    /// nodes are touched (see last_update_touched()). False when not present or the
    /// box is invalid.
    bool move(ItemId id, const Aabb& new_bounds);

    [[nodiscard]] bool contains(ItemId id) const {
        return id < items_.size() && items_[id].node >= 0;
    }
    /// The box of a present item (contains(id)).
    [[nodiscard]] const Aabb& bounds_of(ItemId id) const { return items_[id].bounds; }
    [[nodiscard]] std::size_t size() const { return item_count_; }

    /// Items whose box overlaps `box` (closed), in no particular order: f(ItemId).
    template <class F>
    void query_box(const Aabb& box, F&& f) const {
        visit([&](const OctreeNode& n) { return n.loose_bounds.overlaps(box); },
              [&](const Aabb& b) { return b.overlaps(box); }, f);
    }
    template <class F>
    void query_sphere(const Sphere& sphere, F&& f) const {
        visit([&](const OctreeNode& n) { return overlaps(sphere, n.loose_bounds); },
              [&](const Aabb& b) { return overlaps(sphere, b); }, f);
    }
    /// Conservative: may report items just outside the frustum near its corners.
    template <class F>
    void query_frustum(const Frustum& frustum, F&& f) const {
        visit([&](const OctreeNode& n) { return frustum.may_overlap(n.loose_bounds); },
              [&](const Aabb& b) { return frustum.may_overlap(b); }, f);
    }

    /// Front-to-back traversal from `eye` with occlusion culling: a subtree whose
    /// loose bounds `tester.test_box()` answers `occluded` is skipped; every other
    /// item is tested on its own box and f(ItemId) is called for those `visible`.
    /// `tester` is anything with `Visibility test_box(const Aabb&) const`
    /// (OcclusionBuffer, OcclusionBeams). Order: children by distance from the eye.
    /// Returns the number of subtrees culled.
    template <class Tester, class F>
    int traverse_front_to_back(glm::vec3 eye, const Tester& tester, F&& f) const;

    // Introspection (tests, debugging).
    [[nodiscard]] std::int32_t root() const { return 0; }
    [[nodiscard]] const OctreeNode& node(std::int32_t index) const {
        return nodes_[static_cast<std::size_t>(index)];
    }
    [[nodiscard]] std::size_t live_nodes() const { return nodes_.size() - free_nodes_.size(); }
    /// The node holding a present item (contains(id)).
    [[nodiscard]] std::int32_t node_of(ItemId id) const { return items_[id].node; }
    /// Nodes modified by the last insert/remove/move, and that move's common ancestor.
    [[nodiscard]] const std::vector<std::int32_t>& last_update_touched() const { return touched_; }
    [[nodiscard]] std::int32_t last_update_ancestor() const { return last_ancestor_; }
    [[nodiscard]] const LooseOctreeConfig& config() const { return config_; }

private:
    struct Item {
        Aabb bounds;
        std::int32_t node = -1;
        std::int32_t prev = -1, next = -1;
    };
    struct Target {
        int depth;
        std::uint32_t cell[3];
    };
    [[nodiscard]] Target target_for(const Aabb& bounds) const;
    std::int32_t allocate_node(std::int32_t parent, int depth, const std::uint32_t cell[3]);
    void link(ItemId id, std::int32_t node);
    void unlink(ItemId id);
    /// Walks from `node` up to (excluding) `stop`, subtracting one item and
    /// returning emptied nodes to the pool.
    void release_path(std::int32_t node, std::int32_t stop);
    /// Descends from `from` to `target`, creating nodes, adding one item below `from`.
    std::int32_t descend(std::int32_t from, const Target& target);
    [[nodiscard]] static bool valid_box(const Aabb& b);

    template <class NodeTest, class ItemTest, class F>
    void visit(NodeTest&& node_test, ItemTest&& item_test, F&& f) const {
        std::array<std::int32_t, 8 * 16 + 8> stack;
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const std::int32_t index = stack[--top];
            const OctreeNode& n = nodes_[static_cast<std::size_t>(index)];
            // The root also holds items outside the world bounds: never prune it.
            if (index != 0 && !node_test(n)) {
                continue;
            }
            for (std::int32_t it = n.first_item; it >= 0;
                 it = items_[static_cast<std::size_t>(it)].next) {
                if (item_test(items_[static_cast<std::size_t>(it)].bounds)) {
                    f(static_cast<ItemId>(it));
                }
            }
            for (const std::int32_t c : n.children) {
                if (c >= 0) {
                    stack[top++] = c;
                }
            }
        }
    }

    LooseOctreeConfig config_;
    glm::vec3 origin_{0.0f}; ///< min corner of the root cube
    float root_size_ = 1.0f;
    std::vector<OctreeNode> nodes_;
    std::vector<std::int32_t> free_nodes_;
    std::vector<Item> items_;
    std::size_t item_count_ = 0;
    std::vector<std::int32_t> touched_;
    std::int32_t last_ancestor_ = -1;
};

template <class Tester, class F>
int LooseOctree::traverse_front_to_back(glm::vec3 eye, const Tester& tester, F&& f) const {
    // Depth-first; stack holds at most 7 siblings per level plus the current path.
    std::array<std::int32_t, 8 * 16 + 8> stack;
    int top = 0;
    int culled = 0;
    stack[top++] = 0;
    while (top > 0) {
        const std::int32_t index = stack[--top];
        const OctreeNode& n = nodes_[static_cast<std::size_t>(index)];
        if (!n.has_dynamic_content()) {
            continue;
        }
        // A subtree with a single item is cheaper to decide by the item's own box.
        if (index != 0 && n.subtree_items > 1 &&
            tester.test_box(n.loose_bounds) == Visibility::occluded) {
            ++culled;
            continue;
        }
        for (std::int32_t it = n.first_item; it >= 0;
             it = items_[static_cast<std::size_t>(it)].next) {
            if (tester.test_box(items_[static_cast<std::size_t>(it)].bounds) ==
                Visibility::visible) {
                f(static_cast<ItemId>(it));
            }
        }
        // Push children far-to-near so the nearest pops first.
        std::array<std::pair<float, std::int32_t>, 8> order;
        int count = 0;
        for (const std::int32_t c : n.children) {
            if (c >= 0) {
                order[static_cast<std::size_t>(count++)] = {
                    distance_squared(nodes_[static_cast<std::size_t>(c)].loose_bounds, eye), c};
            }
        }
        for (int i = 1; i < count; ++i) { // insertion sort, farthest first
            const auto key = order[static_cast<std::size_t>(i)];
            int j = i - 1;
            while (j >= 0 && order[static_cast<std::size_t>(j)].first < key.first) {
                order[static_cast<std::size_t>(j + 1)] = order[static_cast<std::size_t>(j)];
                --j;
            }
            order[static_cast<std::size_t>(j + 1)] = key;
        }
        for (int i = 0; i < count; ++i) {
            stack[top++] = order[static_cast<std::size_t>(i)].second;
        }
    }
    return culled;
}

} // namespace dsoc::visibility
