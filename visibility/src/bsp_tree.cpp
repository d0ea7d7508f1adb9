#include "dsoc/visibility/bsp_tree.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace dsoc::visibility {
namespace {

std::uint32_t expand_bits(std::uint32_t v) {
    v = (v * 0x00010001u) & 0xFF0000FFu;
    v = (v * 0x00000101u) & 0x0F00F00Fu;
    v = (v * 0x00000011u) & 0xC30C30C3u;
    v = (v * 0x00000005u) & 0x49249249u;
    return v;
}

std::uint32_t morton(glm::vec3 unit) {
    const auto q = [](float x) {
        return static_cast<std::uint32_t>(std::clamp(x * 1024.0f, 0.0f, 1023.0f));
    };
    return (expand_bits(q(unit.x)) << 2) | (expand_bits(q(unit.y)) << 1) | expand_bits(q(unit.z));
}

bool boxes_separable(const Aabb& a, const Aabb& b) {
    return a.max.x < b.min.x || b.max.x < a.min.x || a.max.y < b.min.y || b.max.y < a.min.y ||
           a.max.z < b.min.z || b.max.z < a.min.z;
}

/// Chooses the plane that best separates children a and b: the widest gap among the
/// three axes (from the boxes) and the centre-to-centre direction (from the spheres).
void choose_split(BspNode& node, const BspNode& a, const BspNode& b) {
    float best_gap = std::numeric_limits<float>::lowest();
    for (int axis = 0; axis < 3; ++axis) {
        // a below b, or b below a.
        const float gap_ab = b.bounds.min[axis] - a.bounds.max[axis];
        const float gap_ba = a.bounds.min[axis] - b.bounds.max[axis];
        glm::vec3 n(0.0f);
        if (gap_ab >= gap_ba && gap_ab > best_gap) {
            n[axis] = 1.0f;
            best_gap = gap_ab;
            node.plane = {n, (a.bounds.max[axis] + b.bounds.min[axis]) * 0.5f};
        } else if (gap_ba > gap_ab && gap_ba > best_gap) {
            n[axis] = -1.0f;
            best_gap = gap_ba;
            node.plane = {n, -(b.bounds.max[axis] + a.bounds.min[axis]) * 0.5f};
        }
    }
    const glm::vec3 d = b.sphere.center - a.sphere.center;
    const float dist = glm::length(d);
    if (dist > 0.0f) {
        const float gap = dist - a.sphere.radius - b.sphere.radius;
        if (gap > best_gap) {
            const glm::vec3 n = d / dist;
            const glm::vec3 mid = a.sphere.center + n * (a.sphere.radius + gap * 0.5f);
            best_gap = gap;
            node.plane = {n, glm::dot(n, mid)};
        }
    }
    node.separated = best_gap > 0.0f;
}

} // namespace

void BspTree::build(const OccluderWorld& world, const BspBuildConfig& config) {
    nodes_.clear();
    root_ = -1;
    depth_ = 0;
    const std::size_t n = world.size();
    if (n == 0) {
        return;
    }
    nodes_.reserve(2 * n - 1);
    std::vector<int> node_depth;
    node_depth.reserve(2 * n - 1);
    Aabb centres;
    for (OccluderId id = 0; id < n; ++id) {
        BspNode leaf;
        leaf.sphere = world.occluder(id).bounding_sphere();
        leaf.bounds = world.occluder(id).bounds();
        leaf.occluder = id;
        nodes_.push_back(leaf);
        node_depth.push_back(1);
        centres.extend(leaf.sphere.center);
    }
    const glm::vec3 scale = 1.0f / glm::max(centres.size(), glm::vec3(1e-6f));

    // Clusters in Morton order.
    std::vector<std::pair<std::uint32_t, std::int32_t>> keyed(n);
    for (std::size_t i = 0; i < n; ++i) {
        keyed[i] = {morton((nodes_[i].sphere.center - centres.min) * scale),
                    static_cast<std::int32_t>(i)};
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<std::int32_t> clusters(n);
    for (std::size_t i = 0; i < n; ++i) {
        clusters[i] = keyed[i].second;
    }

    const int radius = std::clamp(config.search_radius, 1, 256);
    std::vector<std::int32_t> best(n);
    while (clusters.size() > 1) {
        const auto count = static_cast<std::int32_t>(clusters.size());
        for (std::int32_t i = 0; i < count; ++i) {
            float cost = std::numeric_limits<float>::max();
            std::int32_t partner = -1;
            const Sphere& si = nodes_[static_cast<std::size_t>(clusters[i])].sphere;
            const Aabb& bi = nodes_[static_cast<std::size_t>(clusters[i])].bounds;
            const std::int32_t lo = std::max(0, i - radius);
            const std::int32_t hi = std::min(count - 1, i + radius);
            for (std::int32_t j = lo; j <= hi; ++j) {
                if (j == i) {
                    continue;
                }
                const BspNode& nj = nodes_[static_cast<std::size_t>(clusters[j])];
                // Pairs that a plane cannot separate cost double: the tree then
                // prefers splits that are exact visibility orders.
                const float c = enclosing_sphere(si, nj.sphere).radius *
                                (boxes_separable(bi, nj.bounds) ? 1.0f : 2.0f);
                // Ties go to the lower index so mutual picks are symmetric.
                if (c < cost || (c == cost && j < partner)) {
                    cost = c;
                    partner = j;
                }
            }
            best[static_cast<std::size_t>(i)] = partner;
        }
        // Merge mutual best pairs in place; the left partner keeps the new node.
        auto merge = [&](std::int32_t i, std::int32_t j) {
            const std::int32_t a = clusters[static_cast<std::size_t>(i)];
            const std::int32_t b = clusters[static_cast<std::size_t>(j)];
            BspNode node;
            const BspNode& na = nodes_[static_cast<std::size_t>(a)];
            const BspNode& nb = nodes_[static_cast<std::size_t>(b)];
            node.sphere = enclosing_sphere(na.sphere, nb.sphere);
            node.bounds = na.bounds;
            node.bounds.extend(nb.bounds);
            node.children[0] = a;
            node.children[1] = b;
            choose_split(node, na, nb);
            const int d = 1 + std::max(node_depth[static_cast<std::size_t>(a)],
                                       node_depth[static_cast<std::size_t>(b)]);
            nodes_.push_back(node);
            node_depth.push_back(d);
            clusters[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(nodes_.size() - 1);
            clusters[static_cast<std::size_t>(j)] = -1;
        };
        bool merged_any = false;
        for (std::int32_t i = 0; i < count; ++i) {
            const std::int32_t j = best[static_cast<std::size_t>(i)];
            if (j > i && best[static_cast<std::size_t>(j)] == i) {
                merge(i, j);
                merged_any = true;
            }
        }
        if (!merged_any) {
            // Cannot happen (the cheapest pair among all candidates is mutual), but
            // never loop forever.
            merge(0, 1);
        }
        clusters.erase(std::remove(clusters.begin(), clusters.end(), -1), clusters.end());
    }
    root_ = clusters[0];
    depth_ = node_depth[static_cast<std::size_t>(root_)];
}

void BspTree::near_to_far(glm::vec3 eye, float max_distance, std::size_t max_count,
                          std::vector<OccluderId>& out) const {
    out.clear();
    const float max_sq = max_distance * max_distance;
    traverse_near_to_far(
        eye, [&](const BspNode& node) { return distance_squared(node.bounds, eye) <= max_sq; },
        [&](OccluderId id) {
            out.push_back(id);
            return out.size() < max_count;
        });
}

} // namespace dsoc::visibility
