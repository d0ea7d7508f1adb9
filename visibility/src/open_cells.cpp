// The cells a bake pairs: open (not inside one occluder's interior) and covered.

#include "dsoc/visibility/cell_bake.hpp"

#include <utility>

namespace dsoc::visibility {

namespace {

/// How far inside every plane each corner of a solid cell lies. [Units: world units]
constexpr float kSolidMargin = 1.0f / 64.0f;

bool inside_interior(const OccluderWorld& world, OccluderId id, const Aabb& box) {
    for (const Plane& p : world.solid_planes(id)) {
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 corner{(k & 1) != 0 ? box.max.x : box.min.x,
                                   (k & 2) != 0 ? box.max.y : box.min.y,
                                   (k & 4) != 0 ? box.max.z : box.min.z};
            if (p.signed_distance(corner) > -kSolidMargin) {
                return false;
            }
        }
    }
    return true;
}

} // namespace

std::vector<std::uint32_t> open_cells_of(const OccluderScene& scene, const CellGrid& grid,
                                         const BakePruner* pruner) {
    std::vector<std::uint32_t> open;
    OccluderGrid::Scratch scratch;
    const auto n = static_cast<std::uint32_t>(grid.cell_count());
    for (std::uint32_t i = 0; i < n; ++i) {
        const Aabb box = grid.cell_box(grid.coords(i));
        bool solid = pruner != nullptr && pruner->empty_space(box);
        if (!solid && scene.grid != nullptr) {
            scene.grid->query(box, scratch);
            for (const OccluderId id : scratch.found) {
                if (scene.world.occluder(id).bounds().contains(box) &&
                    inside_interior(scene.world, id, box)) {
                    solid = true;
                    break;
                }
            }
        }
        if (!solid) {
            open.push_back(i);
        }
    }
    return open;
}

std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>>
split_covered(std::vector<std::uint32_t> open, std::span<const std::uint8_t> covered) {
    if (covered.empty()) {
        return {std::move(open), {}};
    }
    std::vector<std::uint32_t> uncovered;
    std::erase_if(open, [&](std::uint32_t c) {
        if (c < covered.size() && covered[c] != 0) {
            return false;
        }
        uncovered.push_back(c);
        return true;
    });
    return {std::move(open), std::move(uncovered)};
}

} // namespace dsoc::visibility
