#include "dsoc/visibility/shaft_occlusion.hpp"

#include "dsoc/visibility/reference_visibility.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace dsoc::visibility {

namespace {

std::array<glm::vec3, 8> corners(const Aabb& b) {
    std::array<glm::vec3, 8> c;
    for (int i = 0; i < 8; ++i) {
        c[static_cast<std::size_t>(i)] = glm::vec3(
            (i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z);
    }
    return c;
}

/// Slab test: does the segment from + t * dir, t in [0, 1], touch the closed box?
/// `inv` is 1 / dir per axis (infinite for a zero component, handled below).
bool segment_hits_box(glm::vec3 from, glm::vec3 dir, glm::vec3 inv, const Aabb& box) {
    float t0 = 0.0f;
    float t1 = 1.0f;
    for (int a = 0; a < 3; ++a) {
        if (dir[a] == 0.0f) {
            if (from[a] < box.min[a] || from[a] > box.max[a]) {
                return false;
            }
            continue;
        }
        float ta = (box.min[a] - from[a]) * inv[a];
        float tb = (box.max[a] - from[a]) * inv[a];
        if (ta > tb) {
            std::swap(ta, tb);
        }
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) {
            return false;
        }
    }
    return true;
}

} // namespace

bool shaft_blocked_by(const Aabb& region, const Aabb& box, std::span<const Plane> planes) {
    if (region.is_empty() || box.is_empty() || planes.empty()) {
        return false;
    }
    const auto rc = corners(region);
    const auto bc = corners(box);
    // Cheap rejection first: a plane with every region corner and every box corner
    // strictly outside it cannot be crossed by any segment between them.
    for (const Plane& p : planes) {
        bool all_outside = true;
        for (const auto& c : rc) {
            all_outside = all_outside && p.signed_distance(c) >= 0.0f;
        }
        for (const auto& c : bc) {
            all_outside = all_outside && p.signed_distance(c) >= 0.0f;
        }
        if (all_outside) {
            return false;
        }
    }
    for (const auto& a : rc) {
        for (const auto& b : bc) {
            if (!segment_blocked_by(a, b, planes)) {
                return false;
            }
        }
    }
    return true;
}

OccluderGrid::OccluderGrid(const OccluderWorld& world, float cell_size)
    : world_(&world), bounds_(world.bounds()), cell_size_(cell_size) {
    if (bounds_.is_empty()) {
        cell_start_.assign(2, 0);
        return;
    }
    for (int a = 0; a < 3; ++a) {
        dims_[a] = std::clamp(
            static_cast<int>(std::ceil((bounds_.max[a] - bounds_.min[a]) / cell_size_)), 1, 512);
    }
    const std::size_t cells = static_cast<std::size_t>(dims_[0]) *
                              static_cast<std::size_t>(dims_[1]) *
                              static_cast<std::size_t>(dims_[2]);
    std::vector<std::vector<OccluderId>> lists(cells);
    const auto cell_range = [&](const Aabb& b, int lo[3], int hi[3]) {
        for (int a = 0; a < 3; ++a) {
            lo[a] =
                std::clamp(static_cast<int>(std::floor((b.min[a] - bounds_.min[a]) / cell_size_)),
                           0, dims_[a] - 1);
            hi[a] =
                std::clamp(static_cast<int>(std::floor((b.max[a] - bounds_.min[a]) / cell_size_)),
                           0, dims_[a] - 1);
        }
    };
    for (OccluderId id = 0; id < world.size(); ++id) {
        int lo[3];
        int hi[3];
        cell_range(world.occluder(id).bounds(), lo, hi);
        for (int z = lo[2]; z <= hi[2]; ++z) {
            for (int y = lo[1]; y <= hi[1]; ++y) {
                for (int x = lo[0]; x <= hi[0]; ++x) {
                    lists[static_cast<std::size_t>((z * dims_[1] + y) * dims_[0] + x)].push_back(
                        id);
                }
            }
        }
    }
    cell_start_.reserve(cells + 1);
    cell_start_.push_back(0);
    for (const auto& l : lists) {
        cell_items_.insert(cell_items_.end(), l.begin(), l.end());
        cell_start_.push_back(static_cast<std::uint32_t>(cell_items_.size()));
    }
}

void OccluderGrid::query(const Aabb& box, Scratch& scratch) const {
    scratch.found.clear();
    if (bounds_.is_empty() || !box.overlaps(bounds_)) {
        return;
    }
    if (scratch.stamp.size() != world_->size()) {
        scratch.stamp.assign(world_->size(), 0);
        scratch.epoch = 0;
    }
    if (++scratch.epoch == 0) { // wrapped: reset stamps
        std::fill(scratch.stamp.begin(), scratch.stamp.end(), 0);
        scratch.epoch = 1;
    }
    int lo[3];
    int hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = std::clamp(static_cast<int>(std::floor((box.min[a] - bounds_.min[a]) / cell_size_)),
                           0, dims_[a] - 1);
        hi[a] = std::clamp(static_cast<int>(std::floor((box.max[a] - bounds_.min[a]) / cell_size_)),
                           0, dims_[a] - 1);
    }
    for (int z = lo[2]; z <= hi[2]; ++z) {
        for (int y = lo[1]; y <= hi[1]; ++y) {
            for (int x = lo[0]; x <= hi[0]; ++x) {
                const std::size_t cell =
                    static_cast<std::size_t>((z * dims_[1] + y) * dims_[0] + x);
                for (std::uint32_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
                    const OccluderId id = cell_items_[i];
                    if (scratch.stamp[id] != scratch.epoch) {
                        scratch.stamp[id] = scratch.epoch;
                        if (world_->occluder(id).bounds().overlaps(box)) {
                            scratch.found.push_back(id);
                        }
                    }
                }
            }
        }
    }
}

void OccluderGrid::query_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch) const {
    scratch.found.clear();
    if (bounds_.is_empty()) {
        return;
    }
    if (scratch.stamp.size() != world_->size()) {
        scratch.stamp.assign(world_->size(), 0);
        scratch.epoch = 0;
    }
    if (++scratch.epoch == 0) {
        std::fill(scratch.stamp.begin(), scratch.stamp.end(), 0);
        scratch.epoch = 1;
    }
    // Clip the segment to the grid (slabs), in the segment's parameter t in [0, 1].
    const glm::vec3 dir = to - from;
    float t0 = 0.0f;
    float t1 = 1.0f;
    for (int a = 0; a < 3; ++a) {
        if (std::abs(dir[a]) < 1e-12f) {
            if (from[a] < bounds_.min[a] || from[a] > bounds_.max[a]) {
                return;
            }
            continue;
        }
        float ta = (bounds_.min[a] - from[a]) / dir[a];
        float tb = (bounds_.max[a] - from[a]) / dir[a];
        if (ta > tb) {
            std::swap(ta, tb);
        }
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) {
            return;
        }
    }
    const glm::vec3 start = from + dir * t0;
    int cell[3];
    int step[3];
    float t_max[3];
    float t_delta[3];
    for (int a = 0; a < 3; ++a) {
        cell[a] = std::clamp(static_cast<int>(std::floor((start[a] - bounds_.min[a]) / cell_size_)),
                             0, dims_[a] - 1);
        if (dir[a] > 0.0f) {
            step[a] = 1;
            const float border = bounds_.min[a] + static_cast<float>(cell[a] + 1) * cell_size_;
            t_max[a] = (border - from[a]) / dir[a];
            t_delta[a] = cell_size_ / dir[a];
        } else if (dir[a] < 0.0f) {
            step[a] = -1;
            const float border = bounds_.min[a] + static_cast<float>(cell[a]) * cell_size_;
            t_max[a] = (border - from[a]) / dir[a];
            t_delta[a] = -cell_size_ / dir[a];
        } else {
            step[a] = 0;
            t_max[a] = std::numeric_limits<float>::infinity();
            t_delta[a] = std::numeric_limits<float>::infinity();
        }
    }
    // Every cell is visited at most once per axis step: dims sum bounds the walk.
    for (int guard = dims_[0] + dims_[1] + dims_[2] + 3; guard > 0; --guard) {
        const std::size_t index =
            static_cast<std::size_t>((cell[2] * dims_[1] + cell[1]) * dims_[0] + cell[0]);
        for (std::uint32_t i = cell_start_[index]; i < cell_start_[index + 1]; ++i) {
            const OccluderId id = cell_items_[i];
            if (scratch.stamp[id] != scratch.epoch) {
                scratch.stamp[id] = scratch.epoch;
                scratch.found.push_back(id);
            }
        }
        int axis = 0;
        if (t_max[1] < t_max[axis]) {
            axis = 1;
        }
        if (t_max[2] < t_max[axis]) {
            axis = 2;
        }
        if (t_max[axis] > t1) {
            return;
        }
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] >= dims_[axis]) {
            return;
        }
        t_max[axis] += t_delta[axis];
    }
}

Visibility ShaftOcclusion::test(const Aabb& region, const Aabb& box,
                                OccluderGrid::Scratch& scratch) const {
    if (region.is_empty() || box.is_empty() || region.overlaps(box)) {
        return Visibility::visible;
    }
    const glm::vec3 from = region.center();
    const glm::vec3 to = box.center();
    // Only an occluder that blocks the centre-to-centre segment can pass the first
    // check below, and such an occluder lies in a cell that segment crosses.
    grid_->query_segment(from, to, scratch);
    int full_tests = 0;
    // Occluders that touch or cut into the region count too: the corner argument
    // holds for any convex solid (an eye inside a wall is no eye, and its segments
    // do pass through the wall's interior).
    const glm::vec3 dir = to - from;
    const glm::vec3 inv(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    for (const OccluderId id : scratch.found) {
        if (!segment_hits_box(from, dir, inv, world_->occluder(id).bounds())) {
            continue; // misses the occluder's bounds, so it cannot block the segment
        }
        const auto planes = world_->solid_planes(id);
        // Necessary condition, one segment: the occluder must block centre to centre.
        if (!segment_blocked_by(from, to, planes)) {
            continue;
        }
        if (shaft_blocked_by(region, box, planes)) {
            return Visibility::occluded;
        }
        if (++full_tests >= kMaxFullTests) {
            break; // budget spent: answer visible (conservative)
        }
    }
    return Visibility::visible;
}

} // namespace dsoc::visibility
