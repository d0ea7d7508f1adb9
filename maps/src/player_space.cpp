#include "dsoc/maps/player_space.hpp"

#include "dsoc/visibility/convex_polyhedron.hpp"

#include <glm/common.hpp>

#include <algorithm>
#include <cmath>

namespace dsoc::maps {

std::vector<std::string> validate(const PlayerSpace& space) {
    std::vector<std::string> problems;
    if (!(space.min_walk_normal_z >= 0.0f && space.min_walk_normal_z <= 1.0f)) {
        problems.push_back("min_walk_normal_z must be within 0..1");
    }
    if (!(space.height >= 1.0f && space.height <= 4096.0f)) {
        problems.push_back("height must be within 1..4096 world units");
    }
    if (!(space.margin >= 0.0f && space.margin <= 4096.0f)) {
        problems.push_back("margin must be within 0..4096 world units");
    }
    return problems;
}

std::vector<visibility::Aabb> player_space_boxes(const Map& map, const PlayerSpace& space) {
    std::vector<visibility::Aabb> boxes;
    const glm::vec3 widen{space.margin, space.margin, 0.0f};
    for (const CollisionBrush& brush : map.collision_brushes) {
        visibility::PolyhedronResult result;
        const auto solid = visibility::ConvexPolyhedron::from_planes(brush.planes, result);
        for (const visibility::PolyhedronFace& face : solid.faces()) {
            if (face.plane.normal.z < space.min_walk_normal_z || face.vertex_indices.empty()) {
                continue;
            }
            visibility::Aabb box{glm::vec3(INFINITY), glm::vec3(-INFINITY)};
            for (const std::uint32_t v : face.vertex_indices) {
                box.min = glm::min(box.min, solid.vertices()[v]);
                box.max = glm::max(box.max, solid.vertices()[v]);
            }
            box.min -= widen;
            box.max += widen;
            box.max.z += space.height;
            boxes.push_back(box);
        }
    }
    return boxes;
}

std::vector<std::uint8_t> cells_meeting(const visibility::CellGrid& grid,
                                        const std::vector<visibility::Aabb>& boxes) {
    std::vector<std::uint8_t> cells(grid.cell_count(), 0);
    const visibility::Aabb all = grid.bounds();
    for (const visibility::Aabb& box : boxes) {
        // Clipped to the grid: the part outside has no cells.
        const visibility::Aabb clipped{glm::max(box.min, all.min), glm::min(box.max, all.max)};
        glm::ivec3 lo;
        glm::ivec3 hi;
        if (clipped.is_empty() || !grid.range_of(clipped, lo, hi)) {
            continue;
        }
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                std::uint8_t* row = cells.data() + grid.index({lo.x, y, z});
                std::fill(row, row + (hi.x - lo.x + 1), std::uint8_t{1});
            }
        }
    }
    return cells;
}

} // namespace dsoc::maps
