#include "dsoc/maps/pvs.hpp"

#include <algorithm>
#include <bit>

namespace dsoc::maps {

Pvs::Pvs(const q3::Q3Bsp& bsp, const std::vector<visibility::Aabb>& see_through)
    : num_clusters_(bsp.visibility.num_clusters),
      bytes_per_cluster_(bsp.visibility.bytes_per_cluster), bits_(bsp.visibility.bits) {
    nodes_.reserve(bsp.nodes.size());
    for (const q3::Node& n : bsp.nodes) {
        const q3::Plane& p = bsp.planes[static_cast<std::size_t>(n.plane)];
        nodes_.push_back({p.normal, p.dist, {n.children[0], n.children[1]}});
    }
    leaf_cluster_.reserve(bsp.leafs.size());
    for (const q3::Leaf& l : bsp.leafs) {
        leaf_cluster_.push_back(l.cluster);
    }
    open_through(see_through);
}

void Pvs::open_through(const std::vector<visibility::Aabb>& see_through) {
    if (!has_visibility() || see_through.empty()) {
        return;
    }
    const auto row_bytes = static_cast<std::size_t>(bytes_per_cluster_);
    const auto set_bits = [&] {
        std::uint64_t count = 0;
        for (const std::uint8_t byte : bits_) {
            count += static_cast<std::uint64_t>(std::popcount(byte));
        }
        return count;
    };
    const std::uint64_t before = set_bits();
    // The clusters touching each brush: the leaves around it, one unit out (its own
    // interior is solid leaves, which have none).
    constexpr float kTouch = 1.0f;
    std::vector<std::vector<std::int32_t>> gates;
    for (const visibility::Aabb& brush : see_through) {
        std::vector<std::int32_t> clusters;
        const visibility::Aabb around{brush.min - glm::vec3(kTouch), brush.max + glm::vec3(kTouch)};
        const Walk walked = walk(around, clusters);
        if (walked == Walk::unknown) {
            std::fill(bits_.begin(), bits_.end(), std::uint8_t{0xff}); // cannot tell: all
            opened_pairs_ = set_bits() - before;
            return;
        }
        if (walked == Walk::found) {
            gates.push_back(std::move(clusters));
        }
    }
    std::vector<std::uint8_t> beyond;
    for (bool changed = true; changed;) {
        changed = false;
        for (const std::vector<std::int32_t>& gate : gates) {
            union_of_rows(gate, beyond); // what the clusters around the brush see
            for (std::int32_t from = 0; from < num_clusters_; ++from) {
                std::uint8_t* row = bits_.data() + static_cast<std::size_t>(from) * row_bytes;
                const bool sees_gate = std::any_of(gate.begin(), gate.end(), [&](std::int32_t g) {
                    return g >= num_clusters_ || (row[g >> 3] & (1u << (g & 7))) != 0;
                });
                if (!sees_gate) {
                    continue;
                }
                for (std::size_t i = 0; i < row_bytes; ++i) {
                    const auto opened = static_cast<std::uint8_t>(row[i] | beyond[i]);
                    changed = changed || opened != row[i];
                    row[i] = opened;
                }
            }
        }
    }
    opened_pairs_ = set_bits() - before;
}

bool Pvs::clusters_of(const visibility::Aabb& box, std::vector<std::int32_t>& out) const {
    return walk(box, out) == Walk::found;
}

bool Pvs::touches_no_cluster(const visibility::Aabb& box) const {
    thread_local std::vector<std::int32_t> clusters;
    return walk(box, clusters) == Walk::none;
}

Pvs::Walk Pvs::walk(const visibility::Aabb& box, std::vector<std::int32_t>& out) const {
    out.clear();
    if (leaf_cluster_.empty()) {
        return Walk::unknown;
    }
    // Walk the node tree with the box: both children where the plane cuts it. The
    // stack bound is the tree depth; parse_q3_bsp guarantees children follow parents.
    std::int32_t stack[1024];
    int top = 0;
    stack[top++] = nodes_.empty() ? -1 : 0;
    const glm::vec3 c = box.center();
    const glm::vec3 h = box.half_extents();
    while (top > 0) {
        const std::int32_t index = stack[--top];
        if (index < 0) {
            const std::size_t leaf = static_cast<std::size_t>(-(index + 1));
            if (leaf < leaf_cluster_.size() && leaf_cluster_[leaf] >= 0) {
                out.push_back(leaf_cluster_[leaf]);
            }
            continue;
        }
        const Node& n = nodes_[static_cast<std::size_t>(index)];
        const float d = n.normal.x * c.x + n.normal.y * c.y + n.normal.z * c.z - n.dist;
        const float r =
            std::abs(n.normal.x) * h.x + std::abs(n.normal.y) * h.y + std::abs(n.normal.z) * h.z;
        if (top + 2 > 1024) {
            out.clear(); // pathological depth: answer "may see"
            return Walk::unknown;
        }
        if (d >= -r) {
            stack[top++] = n.children[0];
        }
        if (d < r) {
            stack[top++] = n.children[1];
        }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out.empty() ? Walk::none : Walk::found;
}

void Pvs::union_of_rows(const std::vector<std::int32_t>& clusters,
                        std::vector<std::uint8_t>& out) const {
    out.assign(static_cast<std::size_t>(std::max(bytes_per_cluster_, 0)), 0);
    for (const std::int32_t from : clusters) {
        if (from < 0 || from >= num_clusters_) {
            std::fill(out.begin(), out.end(), std::uint8_t{0xff}); // no answer: all
            return;
        }
        const std::size_t row = static_cast<std::size_t>(from) * out.size();
        for (std::size_t i = 0; i < out.size(); ++i) {
            out[i] |= bits_[row + i];
        }
    }
}

bool Pvs::may_see(const std::vector<std::uint8_t>& visible_clusters, const visibility::Aabb& box,
                  std::vector<std::int32_t>& scratch) const {
    if (!has_visibility() || !clusters_of(box, scratch)) {
        return true;
    }
    return may_see_clusters(visible_clusters, scratch);
}

bool Pvs::may_see_clusters(const std::vector<std::uint8_t>& visible_clusters,
                           const std::vector<std::int32_t>& clusters) const {
    for (const std::int32_t to : clusters) {
        const std::size_t byte = static_cast<std::size_t>(to >> 3);
        if (to >= num_clusters_ || byte >= visible_clusters.size() ||
            (visible_clusters[byte] & (1u << (to & 7))) != 0) {
            return true;
        }
    }
    return false;
}

bool Pvs::cluster_visible(int from, int to) const {
    if (num_clusters_ <= 0 || from < 0 || to < 0 || from >= num_clusters_ || to >= num_clusters_) {
        return true;
    }
    const std::size_t row =
        static_cast<std::size_t>(from) * static_cast<std::size_t>(bytes_per_cluster_);
    return (bits_[row + static_cast<std::size_t>(to >> 3)] & (1u << (to & 7))) != 0;
}

} // namespace dsoc::maps
