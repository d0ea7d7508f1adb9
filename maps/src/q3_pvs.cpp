#include "dsoc/maps/q3_pvs.hpp"

namespace dsoc::maps::q3 {

int find_leaf(const Q3Bsp& bsp, glm::vec3 point) {
    if (bsp.leafs.empty()) {
        return -1;
    }
    if (bsp.nodes.empty()) {
        return 0;
    }
    std::int32_t index = 0;
    // parse_q3_bsp guarantees children > parent and in range, so this ends.
    while (index >= 0) {
        const Node& node = bsp.nodes[static_cast<std::size_t>(index)];
        const Plane& plane = bsp.planes[static_cast<std::size_t>(node.plane)];
        const float d = plane.normal.x * point.x + plane.normal.y * point.y +
                        plane.normal.z * point.z - plane.dist;
        index = d >= 0.0f ? node.children[0] : node.children[1];
    }
    return -(index + 1);
}

int cluster_at(const Q3Bsp& bsp, glm::vec3 point) {
    const int leaf = find_leaf(bsp, point);
    return leaf < 0 ? -1 : bsp.leafs[static_cast<std::size_t>(leaf)].cluster;
}

bool cluster_visible(const Q3Bsp& bsp, int from, int to) {
    const Visibility& vis = bsp.visibility;
    if (vis.num_clusters <= 0 || from < 0 || to < 0 || from >= vis.num_clusters ||
        to >= vis.num_clusters) {
        return true;
    }
    const std::size_t row =
        static_cast<std::size_t>(from) * static_cast<std::size_t>(vis.bytes_per_cluster);
    const std::uint8_t byte = vis.bits[row + static_cast<std::size_t>(to >> 3)];
    return (byte & (1u << (to & 7))) != 0;
}

} // namespace dsoc::maps::q3
