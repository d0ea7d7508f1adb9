#include "dsoc/visibility/shaft_occlusion.hpp"

#include "dsoc/visibility/reference_visibility.hpp"

#include <algorithm>
#include <array>
#include <cmath>

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

Visibility ShaftOcclusion::test(const Aabb& region, const Aabb& box,
                                OccluderGrid::Scratch& scratch) const {
    if (region.is_empty() || box.is_empty() || region.overlaps(box)) {
        return Visibility::visible;
    }
    Aabb shaft = region;
    shaft.extend(box);
    grid_->query(shaft, scratch);
    const glm::vec3 from = region.center();
    const glm::vec3 to = box.center();
    int full_tests = 0;
    // Occluders that touch or cut into the region count too: the corner argument
    // holds for any convex solid (an eye inside a wall is no eye, and its segments
    // do pass through the wall's interior).
    for (const OccluderId id : scratch.found) {
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
