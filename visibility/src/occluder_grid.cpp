#include "dsoc/visibility/occluder_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dsoc::visibility {

namespace {

/// Cells per axis at most: a larger world gets its last cells stretched to its edge
/// (every lookup clamps to the grid the same way, so the lists stay right).
constexpr int kMaxDimension = 512;

int dimension(float extent, float cell_size) {
    return std::clamp(static_cast<int>(std::ceil(extent / cell_size)), 1, kMaxDimension);
}

/// The cell along one axis that holds coordinate `v`, clamped to the grid (so points
/// past its edge fall in its last cells, as the lists were filled).
int cell_at(float v, float grid_min, float cell_size, int dimension) {
    return std::clamp(static_cast<int>(std::floor((v - grid_min) / cell_size)), 0, dimension - 1);
}

/// Entries the cell lists of `world` would hold with cells of `cell_size`.
std::uint64_t list_entries(const OccluderWorld& world, const Aabb& bounds, float cell_size) {
    int dims[3];
    for (int a = 0; a < 3; ++a) {
        dims[a] = dimension(bounds.max[a] - bounds.min[a], cell_size);
    }
    std::uint64_t entries = 0;
    for (OccluderId id = 0; id < world.size(); ++id) {
        const Aabb& b = world.occluder(id).bounds();
        std::uint64_t cells = 1;
        for (int a = 0; a < 3; ++a) {
            cells *= static_cast<std::uint64_t>(
                cell_at(b.max[a], bounds.min[a], cell_size, dims[a]) -
                cell_at(b.min[a], bounds.min[a], cell_size, dims[a]) + 1);
        }
        entries += cells;
    }
    return entries;
}

} // namespace

OccluderGrid::OccluderGrid(const OccluderWorld& world, float cell_size)
    : world_(&world), bounds_(world.bounds()), cell_size_(cell_size) {
    if (bounds_.is_empty()) {
        cell_start_.assign(2, 0);
        return;
    }
    // Coarser until the lists fit their bound: large brushes over fine cells are
    // listed in every cell they overlap.
    while (list_entries(world, bounds_, cell_size_) > kMaxListEntries) {
        cell_size_ *= 2.0f;
    }
    for (int a = 0; a < 3; ++a) {
        dims_[a] = dimension(bounds_.max[a] - bounds_.min[a], cell_size_);
    }
    const std::size_t cells = static_cast<std::size_t>(dims_[0]) *
                              static_cast<std::size_t>(dims_[1]) *
                              static_cast<std::size_t>(dims_[2]);
    std::vector<std::vector<OccluderId>> lists(cells);
    const auto cell_range = [&](const Aabb& b, int lo[3], int hi[3]) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = cell_at(b.min[a], bounds_.min[a], cell_size_, dims_[a]);
            hi[a] = cell_at(b.max[a], bounds_.min[a], cell_size_, dims_[a]);
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
        lo[a] = cell_at(box.min[a], bounds_.min[a], cell_size_, dims_[a]);
        hi[a] = cell_at(box.max[a], bounds_.min[a], cell_size_, dims_[a]);
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

std::span<const OccluderId> OccluderGrid::items_at(glm::vec3 p) const {
    if (bounds_.is_empty()) {
        return {};
    }
    int cell[3];
    for (int a = 0; a < 3; ++a) {
        cell[a] = cell_at(p[a], bounds_.min[a], cell_size_, dims_[a]);
    }
    const std::size_t index =
        static_cast<std::size_t>((cell[2] * dims_[1] + cell[1]) * dims_[0] + cell[0]);
    return {cell_items_.data() + cell_start_[index], cell_start_[index + 1] - cell_start_[index]};
}

void OccluderGrid::query_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch) const {
    scratch.found.clear();
    (void)walk_segment(
        from, to, scratch,
        [](void* found, OccluderId id) {
            static_cast<std::vector<OccluderId>*>(found)->push_back(id);
            return false;
        },
        &scratch.found);
}

bool OccluderGrid::walk_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch, Visit visit,
                                void* context) const {
    if (bounds_.is_empty()) {
        return false;
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
    const glm::vec3 inv(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    float t0 = 0.0f;
    float t1 = 1.0f;
    if (!clip_segment_to_box(from, inv, bounds_, t0, t1)) {
        return false;
    }
    const glm::vec3 start = from + dir * t0;
    // The walk's state: the cell's index, and per axis the parameter t at which the
    // segment leaves the cell's slab (t_max), the step between slabs (t_delta), the
    // index step (stride) and the cells left before the grid's edge. Every float below
    // is what a plain 3D DDA computes, in the same order, so the cells and the
    // occluders found are the same; only the bookkeeping is cheaper (no index
    // arithmetic per cell, no branch on which axis steps).
    float t_max[3];
    float t_delta[3];
    std::ptrdiff_t stride[3];
    int left[3];
    std::ptrdiff_t index = 0;
    const std::ptrdiff_t axis_stride[3] = {1, dims_[0],
                                           static_cast<std::ptrdiff_t>(dims_[0]) * dims_[1]};
    for (int a = 0; a < 3; ++a) {
        const int cell = cell_at(start[a], bounds_.min[a], cell_size_, dims_[a]);
        index += cell * axis_stride[a];
        if (dir[a] > 0.0f) {
            const float border = bounds_.min[a] + static_cast<float>(cell + 1) * cell_size_;
            t_max[a] = (border - from[a]) / dir[a];
            t_delta[a] = cell_size_ / dir[a];
            stride[a] = axis_stride[a];
            left[a] = dims_[a] - 1 - cell;
        } else if (dir[a] < 0.0f) {
            const float border = bounds_.min[a] + static_cast<float>(cell) * cell_size_;
            t_max[a] = (border - from[a]) / dir[a];
            t_delta[a] = -cell_size_ / dir[a];
            stride[a] = -axis_stride[a];
            left[a] = cell;
        } else {
            // Never steps: its t_max is never the least but when all are infinite,
            // and then the walk ends at the t1 check first.
            t_max[a] = std::numeric_limits<float>::infinity();
            t_delta[a] = std::numeric_limits<float>::infinity();
            stride[a] = 0;
            left[a] = 0;
        }
    }
    const std::uint32_t* starts = cell_start_.data();
    float tx = t_max[0];
    float ty = t_max[1];
    float tz = t_max[2];
    // Every cell is visited at most once per axis step: dims sum bounds the walk.
    for (int guard = dims_[0] + dims_[1] + dims_[2] + 3; guard > 0; --guard) {
        const std::uint32_t first = starts[index];
        const std::uint32_t last = starts[index + 1];
        for (std::uint32_t i = first; i < last; ++i) {
            const OccluderId id = cell_items_[i];
            if (scratch.stamp[id] != scratch.epoch) {
                scratch.stamp[id] = scratch.epoch;
                if (visit(context, id)) {
                    return true;
                }
            }
        }
        // The axis whose slab ends first (ties to the lower axis), chosen and stepped
        // without branches: the other axes' t_max get + 0, which leaves them as they are.
        const bool y_first = ty < tx;
        const float t_least = y_first ? ty : tx;
        const bool step_z = tz < t_least;
        const bool step_y = y_first && !step_z;
        const bool step_x = !y_first && !step_z;
        if ((step_z ? tz : t_least) > t1 || (step_z ? left[2] : step_y ? left[1] : left[0]) == 0) {
            return false;
        }
        index += step_z ? stride[2] : step_y ? stride[1] : stride[0];
        left[0] -= static_cast<int>(step_x);
        left[1] -= static_cast<int>(step_y);
        left[2] -= static_cast<int>(step_z);
        tx += step_x ? t_delta[0] : 0.0f;
        ty += step_y ? t_delta[1] : 0.0f;
        tz += step_z ? t_delta[2] : 0.0f;
    }
    return false;
}

} // namespace dsoc::visibility
