#include "dsoc/sim/collision_world.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace dsoc::sim {
namespace {

/// Grid budget: the cell size doubles until the grid has at most this many cells.
constexpr std::size_t kMaxCells = 1u << 21;
constexpr float kMinCellSize = 128.0f;

/// Distance the plane moves out when the box [mins, maxs] slides along it:
/// -min over the box corners of dot(n, corner).
float support_offset(glm::vec3 n, glm::vec3 mins, glm::vec3 maxs) {
    return -(std::min(n.x * mins.x, n.x * maxs.x) + std::min(n.y * mins.y, n.y * maxs.y) +
             std::min(n.z * mins.z, n.z * maxs.z));
}

} // namespace

CollisionWorld::CollisionWorld(std::span<const maps::CollisionBrush> brushes,
                               std::uint32_t contents_mask) {
    for (const maps::CollisionBrush& source : brushes) {
        if ((source.contents & contents_mask) == 0 || source.bounds.is_empty()) {
            continue;
        }
        Brush brush;
        brush.first_plane = static_cast<std::uint32_t>(planes_.size());
        brush.plane_count = static_cast<std::uint32_t>(source.planes.size());
        brush.bounds = source.bounds;
        planes_.insert(planes_.end(), source.planes.begin(), source.planes.end());
        bounds_.extend(source.bounds);
        brushes_.push_back(brush);
    }
    build_grid();
}

std::int32_t CollisionWorld::cell_coordinate(float value, int axis) const {
    // Clamped before the conversion: any finite value maps into the grid.
    const float cell = std::floor((value - bounds_.min[axis]) / cell_size_);
    return static_cast<std::int32_t>(std::clamp(cell, 0.0f, static_cast<float>(dims_[axis] - 1)));
}

void CollisionWorld::build_grid() {
    if (brushes_.empty()) {
        return;
    }
    const glm::vec3 size = bounds_.size();
    cell_size_ = kMinCellSize;
    for (;;) {
        // In double, so that a huge (hostile) map cannot overflow the cell counts.
        double cells = 1.0;
        for (int a = 0; a < 3; ++a) {
            cells *= std::max(1.0, std::ceil(static_cast<double>(size[a]) / cell_size_));
        }
        if (cells <= static_cast<double>(kMaxCells)) {
            for (int a = 0; a < 3; ++a) {
                dims_[a] = static_cast<std::int32_t>(
                    std::max(1.0, std::ceil(static_cast<double>(size[a]) / cell_size_)));
            }
            break;
        }
        cell_size_ *= 2.0f;
    }
    auto cell_range = [&](const visibility::Aabb& box, std::int32_t lo[3], std::int32_t hi[3]) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = cell_coordinate(box.min[a], a);
            hi[a] = cell_coordinate(box.max[a], a);
        }
    };
    const std::size_t cell_count = static_cast<std::size_t>(dims_[0]) *
                                   static_cast<std::size_t>(dims_[1]) *
                                   static_cast<std::size_t>(dims_[2]);
    cell_start_.assign(cell_count + 1, 0);
    auto for_cells = [&](Brush& brush, auto&& visit) {
        std::int32_t lo[3];
        std::int32_t hi[3];
        cell_range(brush.bounds, lo, hi);
        std::copy(lo, lo + 3, brush.cell_min);
        for (std::int32_t z = lo[2]; z <= hi[2]; ++z) {
            for (std::int32_t y = lo[1]; y <= hi[1]; ++y) {
                for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
                    visit((static_cast<std::size_t>(z) * static_cast<std::size_t>(dims_[1]) +
                           static_cast<std::size_t>(y)) *
                              static_cast<std::size_t>(dims_[0]) +
                          static_cast<std::size_t>(x));
                }
            }
        }
    };
    for (Brush& brush : brushes_) {
        for_cells(brush, [&](std::size_t cell) { ++cell_start_[cell + 1]; });
    }
    for (std::size_t c = 0; c < cell_count; ++c) {
        cell_start_[c + 1] += cell_start_[c];
    }
    cell_brushes_.resize(cell_start_[cell_count]);
    std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::uint32_t i = 0; i < brushes_.size(); ++i) {
        for_cells(brushes_[i], [&](std::size_t cell) { cell_brushes_[fill[cell]++] = i; });
    }
}

template <class Visit>
void CollisionWorld::for_each_candidate(const visibility::Aabb& query, Visit&& visit) const {
    if (brushes_.empty() || !query.overlaps(bounds_)) {
        return;
    }
    std::int32_t lo[3];
    std::int32_t hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = cell_coordinate(query.min[a], a);
        hi[a] = cell_coordinate(query.max[a], a);
    }
    for (std::int32_t z = lo[2]; z <= hi[2]; ++z) {
        for (std::int32_t y = lo[1]; y <= hi[1]; ++y) {
            for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
                const std::size_t cell =
                    (static_cast<std::size_t>(z) * static_cast<std::size_t>(dims_[1]) +
                     static_cast<std::size_t>(y)) *
                        static_cast<std::size_t>(dims_[0]) +
                    static_cast<std::size_t>(x);
                for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
                    const std::uint32_t index = cell_brushes_[k];
                    const Brush& brush = brushes_[index];
                    // Visit each brush once: in the first cell shared by the query
                    // range and the brush's range.
                    if (x != std::max(lo[0], brush.cell_min[0]) ||
                        y != std::max(lo[1], brush.cell_min[1]) ||
                        z != std::max(lo[2], brush.cell_min[2])) {
                        continue;
                    }
                    if (brush.bounds.overlaps(query)) {
                        visit(index);
                    }
                }
            }
        }
    }
}

void CollisionWorld::clip_brush(std::uint32_t index, glm::vec3 start, glm::vec3 end, glm::vec3 mins,
                                glm::vec3 maxs, BoxTrace& trace) const {
    const Brush& brush = brushes_[index];
    float enter = -1.0f;
    float leave = 1.0f;
    const visibility::Plane* clip_plane = nullptr;
    bool starts_out = false;
    bool gets_out = false;
    for (std::uint32_t p = 0; p < brush.plane_count; ++p) {
        const visibility::Plane& plane = planes_[brush.first_plane + p];
        const float distance = plane.distance + support_offset(plane.normal, mins, maxs);
        const float d1 = glm::dot(start, plane.normal) - distance;
        const float d2 = glm::dot(end, plane.normal) - distance;
        if (d2 > 0.0f) {
            gets_out = true;
        }
        if (d1 > 0.0f) {
            starts_out = true;
        }
        // Completely in front of this plane: the trace misses the brush.
        if (d1 > 0.0f && (d2 >= kSurfaceClipEpsilon || d2 >= d1)) {
            return;
        }
        if (d1 <= 0.0f && d2 <= 0.0f) {
            continue;
        }
        if (d1 > d2) { // entering
            const float f = std::max(0.0f, (d1 - kSurfaceClipEpsilon) / (d1 - d2));
            if (f > enter) {
                enter = f;
                clip_plane = &plane;
            }
        } else { // leaving
            const float f = std::min(1.0f, (d1 + kSurfaceClipEpsilon) / (d1 - d2));
            leave = std::min(leave, f);
        }
    }
    if (!starts_out) {
        trace.start_solid = true;
        if (!gets_out) {
            trace.all_solid = true;
            trace.fraction = 0.0f;
            trace.brush = static_cast<std::int32_t>(index);
        }
        return;
    }
    if (enter < leave && enter > -1.0f && enter < trace.fraction && clip_plane != nullptr) {
        trace.fraction = std::max(enter, 0.0f);
        trace.hit_normal = clip_plane->normal;
        trace.brush = static_cast<std::int32_t>(index);
    }
}

BoxTrace CollisionWorld::trace_box(glm::vec3 start, glm::vec3 end, glm::vec3 mins,
                                   glm::vec3 maxs) const {
    BoxTrace trace;
    visibility::Aabb query = visibility::Aabb::empty();
    query.extend(start + mins);
    query.extend(start + maxs);
    query.extend(end + mins);
    query.extend(end + maxs);
    query = query.expanded(1.0f);
    for_each_candidate(query, [&](std::uint32_t index) {
        if (!trace.all_solid) {
            clip_brush(index, start, end, mins, maxs, trace);
        }
    });
    trace.end_position = trace.fraction >= 1.0f ? end : start + (end - start) * trace.fraction;
    return trace;
}

bool CollisionWorld::box_in_solid(glm::vec3 origin, glm::vec3 mins, glm::vec3 maxs,
                                  float tolerance) const {
    const glm::vec3 shrink(tolerance);
    const glm::vec3 lo = glm::min(mins + shrink, maxs);
    const glm::vec3 hi = glm::max(maxs - shrink, lo);
    bool inside = false;
    visibility::Aabb query{origin + lo, origin + hi};
    for_each_candidate(query, [&](std::uint32_t index) {
        if (inside) {
            return;
        }
        const Brush& brush = brushes_[index];
        bool all_behind = true;
        for (std::uint32_t p = 0; p < brush.plane_count && all_behind; ++p) {
            const visibility::Plane& plane = planes_[brush.first_plane + p];
            all_behind = glm::dot(origin, plane.normal) - plane.distance -
                             support_offset(plane.normal, lo, hi) <
                         0.0f;
        }
        inside = all_behind;
    });
    return inside;
}

} // namespace dsoc::sim
