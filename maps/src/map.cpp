#include "dsoc/maps/map.hpp"

#include "brush_builder.hpp"

#include <glm/geometric.hpp>

namespace dsoc::maps {

void add_axial_bevels(std::vector<visibility::Plane>& planes, const visibility::Aabb& bounds) {
    for (int axis = 0; axis < 3; ++axis) {
        for (const float sign : {-1.0f, 1.0f}) {
            glm::vec3 normal(0.0f);
            normal[axis] = sign;
            bool present = false;
            for (const visibility::Plane& plane : planes) {
                present = present || glm::dot(plane.normal, normal) > 0.9999f;
            }
            if (!present) {
                const float distance = sign > 0 ? bounds.max[axis] : -bounds.min[axis];
                planes.push_back({normal, distance});
            }
        }
    }
}

namespace detail {

bool add_brush(Map& map, std::span<const visibility::Plane> planes, std::uint32_t contents,
               bool opaque) {
    ++map.stats.collision_candidates;
    if (opaque) {
        ++map.stats.opaque_candidates;
    }
    if (planes.size() > kMaxBrushPlanes) {
        ++map.stats.degenerate.too_many_planes;
        return false;
    }
    visibility::PolyhedronResult result;
    visibility::ConvexPolyhedron solid =
        visibility::ConvexPolyhedron::from_planes(planes, result, kBrushTolerance);
    if (!result.ok()) {
        DegenerateCounts& counts = map.stats.degenerate;
        switch (result.error) {
        case visibility::PolyhedronError::too_few_planes:
            ++counts.too_few_planes;
            break;
        case visibility::PolyhedronError::non_finite_plane:
            ++counts.non_finite_plane;
            break;
        case visibility::PolyhedronError::unbounded:
            ++counts.unbounded;
            break;
        case visibility::PolyhedronError::empty:
        case visibility::PolyhedronError::none:
            ++counts.empty;
            break;
        }
        return false;
    }
    CollisionBrush brush;
    brush.bounds = solid.bounds();
    brush.contents = contents;
    brush.planes.reserve(planes.size() + 6);
    for (const visibility::Plane& plane : planes) {
        const float length = glm::length(plane.normal);
        brush.planes.push_back({plane.normal / length, plane.distance / length});
    }
    add_axial_bevels(brush.planes, brush.bounds);
    map.collision_brushes.push_back(std::move(brush));
    if (opaque) {
        map.occluders.push_back(std::move(solid));
    }
    return true;
}

void finish_map(Map& map) {
    map.bounds = visibility::Aabb::empty();
    for (const CollisionBrush& brush : map.collision_brushes) {
        map.bounds.extend(brush.bounds);
    }
    map.stats.opaque_occluders = map.occluders.size();
    map.stats.collision_brushes = map.collision_brushes.size();
}

} // namespace detail
} // namespace dsoc::maps
