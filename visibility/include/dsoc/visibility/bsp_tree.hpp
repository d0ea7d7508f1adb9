#pragma once
// Bottom-up BSP tree over the static occluders (the "BSP tree" of the occlusion-beam
// seed): leaves are occluders; every inner node pairs two subtrees whose merged
// containment sphere is small, with a plane separating them and a containment sphere
// and box around them. Traversal from an eye visits occluders near-to-far.

#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace dsoc::visibility {

/// One node of BspTree::nodes(); indexes are into that vector.
struct BspNode {
    /// Inner nodes: child 0 lies on the negative side (signed_distance <= 0) as far
    /// as the split is exact (see `separated`). Leaves: unused.
    Plane plane;
    /// Contains every occluder of the subtree.
    Sphere sphere;
    Aabb bounds;
    /// Children node indexes (inner) or {-1, -1} (leaf).
    std::int32_t children[2] = {-1, -1};
    /// The occluder of a leaf, OccluderWorld::kInvalid for inner nodes.
    OccluderId occluder = OccluderWorld::kInvalid;
    /// True when the plane strictly separates the two children's bounds, so visiting
    /// the eye's side first is a correct visibility order for this node. False when
    /// the children overlap (then the order is by the best available plane).
    bool separated = false;
    [[nodiscard]] bool is_leaf() const { return children[0] < 0; }
};

struct BspBuildConfig {
    /// How many neighbours (in Morton order) each cluster considers when looking for
    /// its cheapest partner. Larger = closer to the exact greedy pairing, slower.
    /// [Units: clusters] [Limit: 1..256]
    int search_radius = 16;
};

/// Immutable after build(); all const members are safe to call concurrently.
class BspTree {
public:
    /// Maximum depth a traversal handles; deeper subtrees are not visited (build()
    /// reports the depth; the builder keeps it logarithmic in practice).
    static constexpr int kMaxTraversalDepth = 256;

    /// Builds over every occluder of `world`. O(n log n) expected: locally-ordered
    /// agglomerative clustering (Walter et al. 2008, PLOC by Meister & Bittner 2018):
    /// clusters sorted along a Morton curve each pick the partner within
    /// `search_radius` whose merged containment sphere is smallest; mutual picks merge.
    void build(const OccluderWorld& world, const BspBuildConfig& config = {});

    [[nodiscard]] bool empty() const { return nodes_.empty(); }
    [[nodiscard]] std::int32_t root() const { return root_; }
    [[nodiscard]] const std::vector<BspNode>& nodes() const { return nodes_; }
    [[nodiscard]] int depth() const { return depth_; }

    /// Visits the tree from `eye`, near side first at every node.
    /// `enter(const BspNode&) -> bool`: called for every node reached; false skips its
    /// subtree. `leaf(OccluderId) -> bool`: called for each leaf entered; false stops
    /// the whole traversal.
    template <class Enter, class Leaf>
    void traverse_near_to_far(glm::vec3 eye, Enter&& enter, Leaf&& leaf) const {
        if (root_ < 0) {
            return;
        }
        std::array<std::int32_t, kMaxTraversalDepth> stack;
        int top = 0;
        stack[top++] = root_;
        while (top > 0) {
            const BspNode& node = nodes_[static_cast<std::size_t>(stack[--top])];
            if (const Step step = visit(node, enter, leaf); step != Step::descend) {
                if (step == Step::stop) {
                    return;
                }
                continue;
            }
            const int near = node.plane.signed_distance(eye) <= 0.0f ? 0 : 1;
            if (top + 2 <= kMaxTraversalDepth) {
                stack[top++] = node.children[1 - near];
                stack[top++] = node.children[near];
            }
        }
    }

    /// Visits the tree best-first by the distance from `eye` to each node's bounds, so
    /// leaves come in increasing order of their bounds' distance (ties and overlaps
    /// aside). This is the order to spend an occluder budget in: a depth-first BSP
    /// order finishes the whole near half-space before the nearest occluder across
    /// the root plane. Same callbacks as traverse_near_to_far; `heap` is scratch
    /// memory reused across calls (one per thread).
    template <class Enter, class Leaf>
    void traverse_nearest_first(glm::vec3 eye, std::vector<std::pair<float, std::int32_t>>& heap,
                                Enter&& enter, Leaf&& leaf) const {
        heap.clear();
        if (root_ < 0) {
            return;
        }
        const auto cmp = [](const std::pair<float, std::int32_t>& a,
                            const std::pair<float, std::int32_t>& b) { return a.first > b.first; };
        heap.emplace_back(distance_squared(nodes_[static_cast<std::size_t>(root_)].bounds, eye),
                          root_);
        while (!heap.empty()) {
            std::pop_heap(heap.begin(), heap.end(), cmp);
            const BspNode& node = nodes_[static_cast<std::size_t>(heap.back().second)];
            heap.pop_back();
            if (const Step step = visit(node, enter, leaf); step != Step::descend) {
                if (step == Step::stop) {
                    return;
                }
                continue;
            }
            for (const std::int32_t c : node.children) {
                heap.emplace_back(distance_squared(nodes_[static_cast<std::size_t>(c)].bounds, eye),
                                  c);
                std::push_heap(heap.begin(), heap.end(), cmp);
            }
        }
    }

    /// Occluders near-to-far whose bounds come within `max_distance` of `eye`,
    /// at most `max_count`, appended to `out` (cleared first).
    void near_to_far(glm::vec3 eye, float max_distance, std::size_t max_count,
                     std::vector<OccluderId>& out) const;

private:
    enum class Step : std::uint8_t { skip, stop, descend };
    /// What both traversals do at a node: `enter` refuses it (skip), a leaf's callback
    /// stops the walk (stop) or not (skip), or an inner node's children come next.
    template <class Enter, class Leaf>
    static Step visit(const BspNode& node, Enter& enter, Leaf& leaf) {
        if (!enter(node)) {
            return Step::skip;
        }
        if (node.is_leaf()) {
            return leaf(node.occluder) ? Step::skip : Step::stop;
        }
        return Step::descend;
    }

    std::vector<BspNode> nodes_;
    std::int32_t root_ = -1;
    int depth_ = 0;
};

} // namespace dsoc::visibility
