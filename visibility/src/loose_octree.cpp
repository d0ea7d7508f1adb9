#include "dsoc/visibility/loose_octree.hpp"

#include <cmath>

namespace dsoc::visibility {

LooseOctree::LooseOctree(const LooseOctreeConfig& config) : config_(config) {
    config_.max_depth = std::clamp(config_.max_depth, 0, 15);
    config_.max_items = std::max<std::uint32_t>(config_.max_items, 1);
    Aabb wb = config_.world_bounds;
    if (wb.is_empty()) {
        wb = LooseOctreeConfig{}.world_bounds;
    }
    const glm::vec3 size = wb.size();
    root_size_ = std::max(std::max(size.x, size.y), std::max(size.z, 1.0f));
    origin_ = wb.center() - glm::vec3(root_size_ * 0.5f);
    // Item and node storage grows with use (insert()): a client's tree is built when it
    // joins, and most hold few TBVs, so nothing is allocated for max_items up front.
    const std::uint32_t zero[3] = {0, 0, 0};
    allocate_node(-1, 0, zero);
}

bool LooseOctree::valid_box(const Aabb& b) {
    return !b.is_empty() && std::isfinite(b.min.x) && std::isfinite(b.min.y) &&
           std::isfinite(b.min.z) && std::isfinite(b.max.x) && std::isfinite(b.max.y) &&
           std::isfinite(b.max.z);
}

LooseOctree::Target LooseOctree::target_for(const Aabb& bounds) const {
    const glm::vec3 half = bounds.half_extents();
    const float largest = std::max(half.x, std::max(half.y, half.z));
    const glm::vec3 c = bounds.center();
    Target t{0, {0, 0, 0}};
    // Outside the root cube (by more than the looseness allows): keep at the root.
    const glm::vec3 rel = (c - origin_) / root_size_;
    if (rel.x < 0.0f || rel.y < 0.0f || rel.z < 0.0f || rel.x >= 1.0f || rel.y >= 1.0f ||
        rel.z >= 1.0f) {
        return t;
    }
    // Deepest level whose cell size s satisfies largest <= s / 2.
    int depth = 0;
    float cell = root_size_;
    while (depth < config_.max_depth && largest <= cell * 0.25f) {
        cell *= 0.5f;
        ++depth;
    }
    const auto cells = static_cast<float>(1u << depth);
    t.depth = depth;
    for (int a = 0; a < 3; ++a) {
        const float v = std::floor(rel[a] * cells);
        t.cell[a] = static_cast<std::uint32_t>(std::clamp(v, 0.0f, cells - 1.0f));
    }
    return t;
}

std::int32_t LooseOctree::allocate_node(std::int32_t parent, int depth,
                                        const std::uint32_t cell[3]) {
    std::int32_t index;
    if (!free_nodes_.empty()) {
        index = free_nodes_.back();
        free_nodes_.pop_back();
    } else {
        index = static_cast<std::int32_t>(nodes_.size());
        nodes_.emplace_back();
    }
    OctreeNode& n = nodes_[static_cast<std::size_t>(index)];
    n = OctreeNode{};
    n.parent = parent;
    n.depth = static_cast<std::uint8_t>(depth);
    const float size = root_size_ / static_cast<float>(1u << depth);
    glm::vec3 lo;
    for (int a = 0; a < 3; ++a) {
        n.cell[a] = cell[a];
        lo[a] = origin_[a] + static_cast<float>(cell[a]) * size;
    }
    n.loose_bounds = {lo - glm::vec3(size * 0.5f), lo + glm::vec3(size * 1.5f)};
    if (depth == 0) {
        n.loose_bounds = {origin_ - glm::vec3(root_size_ * 0.5f),
                          origin_ + glm::vec3(root_size_ * 1.5f)};
    }
    return index;
}

void LooseOctree::link(ItemId id, std::int32_t node) {
    Item& item = items_[id];
    OctreeNode& n = nodes_[static_cast<std::size_t>(node)];
    item.node = node;
    item.prev = -1;
    item.next = n.first_item;
    if (n.first_item >= 0) {
        items_[static_cast<std::size_t>(n.first_item)].prev = static_cast<std::int32_t>(id);
    }
    n.first_item = static_cast<std::int32_t>(id);
}

void LooseOctree::unlink(ItemId id) {
    Item& item = items_[id];
    OctreeNode& n = nodes_[static_cast<std::size_t>(item.node)];
    if (item.prev >= 0) {
        items_[static_cast<std::size_t>(item.prev)].next = item.next;
    } else {
        n.first_item = item.next;
    }
    if (item.next >= 0) {
        items_[static_cast<std::size_t>(item.next)].prev = item.prev;
    }
    item.node = -1;
    item.prev = item.next = -1;
}

void LooseOctree::release_path(std::int32_t node, std::int32_t stop) {
    while (node != stop && node >= 0) {
        OctreeNode& n = nodes_[static_cast<std::size_t>(node)];
        touched_.push_back(node);
        --n.subtree_items;
        const std::int32_t parent = n.parent;
        if (n.subtree_items == 0 && node != 0) {
            // Empty subtree: detach from the parent and return to the pool.
            OctreeNode& p = nodes_[static_cast<std::size_t>(parent)];
            for (std::int32_t& c : p.children) {
                if (c == node) {
                    c = -1;
                }
            }
            free_nodes_.push_back(node);
        }
        node = parent;
    }
}

std::int32_t LooseOctree::descend(std::int32_t from, const Target& target) {
    std::int32_t node = from;
    for (int d = nodes_[static_cast<std::size_t>(from)].depth; d < target.depth; ++d) {
        const int shift = target.depth - d - 1;
        std::uint32_t cell[3];
        int child = 0;
        for (int a = 0; a < 3; ++a) {
            cell[a] = target.cell[a] >> shift;
            child |= static_cast<int>(cell[a] & 1u) << a;
        }
        std::int32_t next =
            nodes_[static_cast<std::size_t>(node)].children[static_cast<std::size_t>(child)];
        if (next < 0) {
            next = allocate_node(node, d + 1, cell); // may reallocate nodes_
            nodes_[static_cast<std::size_t>(node)].children[static_cast<std::size_t>(child)] = next;
        }
        node = next;
        nodes_[static_cast<std::size_t>(node)].subtree_items += 1;
        touched_.push_back(node);
    }
    return node;
}

bool LooseOctree::insert(ItemId id, const Aabb& bounds) {
    if (id >= config_.max_items || contains(id) || !valid_box(bounds)) {
        return false;
    }
    if (id >= items_.size()) { // doubling, up to max_items
        items_.resize(std::min<std::size_t>(
            config_.max_items,
            std::max<std::size_t>({std::size_t{id} + 1, 2 * items_.size(), 64})));
    }
    touched_.clear();
    const Target t = target_for(bounds);
    nodes_[0].subtree_items += 1;
    touched_.push_back(0);
    const std::int32_t node = descend(0, t);
    items_[id].bounds = bounds;
    link(id, node);
    last_ancestor_ = 0;
    ++item_count_;
    return true;
}

bool LooseOctree::remove(ItemId id) {
    if (!contains(id)) {
        return false;
    }
    touched_.clear();
    const std::int32_t node = items_[id].node;
    unlink(id);
    release_path(node, -1);
    last_ancestor_ = 0;
    --item_count_;
    return true;
}

bool LooseOctree::move(ItemId id, const Aabb& new_bounds) {
    if (!contains(id) || !valid_box(new_bounds)) {
        return false;
    }
    touched_.clear();
    const std::int32_t old_node = items_[id].node;
    const OctreeNode& old = nodes_[static_cast<std::size_t>(old_node)];
    const Target t = target_for(new_bounds);
    items_[id].bounds = new_bounds;
    // Deepest common prefix of the old node's path and the new target's path.
    int common = std::min<int>(old.depth, t.depth);
    while (common > 0) {
        bool same = true;
        for (int a = 0; a < 3; ++a) {
            same =
                same && (old.cell[a] >> (old.depth - common)) == (t.cell[a] >> (t.depth - common));
        }
        if (same) {
            break;
        }
        --common;
    }
    std::int32_t ancestor = old_node;
    while (nodes_[static_cast<std::size_t>(ancestor)].depth > common) {
        ancestor = nodes_[static_cast<std::size_t>(ancestor)].parent;
    }
    last_ancestor_ = ancestor;
    if (ancestor == old_node && t.depth == old.depth) {
        touched_.push_back(old_node); // same node: only the item's box changed
        return true;
    }
    // Take the item out below the ancestor (the ancestor keeps its count), then put
    // it back in below the ancestor.
    unlink(id);
    touched_.push_back(ancestor);
    release_path(old_node, ancestor);
    const std::int32_t node = descend(ancestor, t);
    link(id, node);
    return true;
}

} // namespace dsoc::visibility
