#include "dsoc/visibility/occluder_bvh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace dsoc::visibility {

namespace {

/// Surface area of a box (0 for an empty one): the surface area heuristic's weight for
/// the chance that a segment touches it.
float area(const Aabb& b) {
    if (b.is_empty()) {
        return 0.0f;
    }
    const glm::vec3 e = b.size();
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

/// Reorders ids[lo, hi) (two or more) into two non-empty parts and returns where the
/// second starts: the split by centre along an axis, among kBins candidates per axis,
/// that the surface area heuristic rates cheapest (each part's area times its count), so
/// that a floor under the whole map ends up alone, not in every node above its leaf;
/// the median along the widest axis when the centres coincide or `balanced` asks for it.
std::size_t split_ids(const std::vector<Aabb>& bounds, std::vector<OccluderId>& ids, std::size_t lo,
                      std::size_t hi, bool balanced) {
    constexpr int kBins = 12;
    Aabb centres;
    for (std::size_t i = lo; i < hi; ++i) {
        centres.extend(bounds[ids[i]].center());
    }
    const glm::vec3 spread = centres.max - centres.min;
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1;
    float best_cut = 0.0f;
    for (int axis = 0; axis < 3 && !balanced; ++axis) {
        // Centres that coincide on this axis, or lie a subnormal apart (the scale would
        // overflow, and a bin's index be no number): no split along it.
        const float scale = static_cast<float>(kBins) / spread[axis];
        if (!(spread[axis] > 0.0f) || !std::isfinite(scale)) {
            continue;
        }
        Aabb bin_box[kBins];
        std::size_t bin_count[kBins] = {};
        const auto bin_of = [&](OccluderId id) {
            const float c = bounds[id].center()[axis];
            return std::clamp(static_cast<int>((c - centres.min[axis]) * scale), 0, kBins - 1);
        };
        for (std::size_t i = lo; i < hi; ++i) {
            const int b = bin_of(ids[i]);
            bin_box[b].extend(bounds[ids[i]]);
            ++bin_count[b];
        }
        // Left parts from below, right parts from above; a cut after bin k.
        float right_area[kBins];
        std::size_t right_count[kBins];
        Aabb acc;
        std::size_t n = 0;
        for (int b = kBins - 1; b > 0; --b) {
            acc.extend(bin_box[b]);
            n += bin_count[b];
            right_area[b] = area(acc);
            right_count[b] = n;
        }
        acc = Aabb{};
        n = 0;
        for (int b = 0; b + 1 < kBins; ++b) {
            acc.extend(bin_box[b]);
            n += bin_count[b];
            if (n == 0 || right_count[b + 1] == 0) {
                continue;
            }
            const float cost = area(acc) * static_cast<float>(n) +
                               right_area[b + 1] * static_cast<float>(right_count[b + 1]);
            if (cost < best_cost) {
                best_cost = cost;
                best_axis = axis;
                best_cut = centres.min[axis] + static_cast<float>(b + 1) / scale;
            }
        }
    }
    if (best_axis >= 0) {
        const int axis = best_axis;
        const float cut = best_cut;
        // The same binning as above decides the side, so both parts are non-empty.
        const float scale = static_cast<float>(kBins) / spread[axis];
        const int cut_bin =
            std::clamp(static_cast<int>((cut - centres.min[axis]) * scale + 0.5f), 1, kBins - 1);
        const auto middle =
            std::partition(ids.begin() + static_cast<std::ptrdiff_t>(lo),
                           ids.begin() + static_cast<std::ptrdiff_t>(hi), [&](OccluderId id) {
                               const float c = bounds[id].center()[axis];
                               return std::clamp(static_cast<int>((c - centres.min[axis]) * scale),
                                                 0, kBins - 1) < cut_bin;
                           });
        const auto at = static_cast<std::size_t>(middle - ids.begin());
        if (at > lo && at < hi) {
            return at;
        }
    }
    const int axis =
        spread.x >= spread.y && spread.x >= spread.z ? 0 : (spread.y >= spread.z ? 1 : 2);
    const std::size_t middle = lo + (hi - lo) / 2;
    std::nth_element(ids.begin() + static_cast<std::ptrdiff_t>(lo),
                     ids.begin() + static_cast<std::ptrdiff_t>(middle),
                     ids.begin() + static_cast<std::ptrdiff_t>(hi),
                     [&](OccluderId a, OccluderId b) {
                         return bounds[a].min[axis] + bounds[a].max[axis] <
                                bounds[b].min[axis] + bounds[b].max[axis];
                     });
    return middle;
}

} // namespace

OccluderBvh::OccluderBvh(const OccluderWorld& world, int sah_levels)
    : sah_levels_(std::clamp(sah_levels, 0, kSahLevels)), occluders_(world.size()) {
    if (occluders_ == 0) {
        return;
    }
    std::vector<Aabb> bounds;
    bounds.reserve(occluders_);
    for (OccluderId id = 0; id < occluders_; ++id) {
        bounds.push_back(world.occluder(id).bounds());
    }
    std::vector<OccluderId> ids(occluders_);
    std::iota(ids.begin(), ids.end(), OccluderId{0});
    (void)build(bounds, ids, 0, ids.size(), 0);
}

std::uint32_t OccluderBvh::slot(const std::vector<Aabb>& bounds, std::vector<OccluderId>& ids,
                                std::size_t begin, std::size_t end, int depth) {
    return end - begin == 1 ? kItem | ids[begin] : build(bounds, ids, begin, end, depth);
}

std::uint32_t OccluderBvh::build(const std::vector<Aabb>& bounds, std::vector<OccluderId>& ids,
                                 std::size_t begin, std::size_t end, int depth) {
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    depth_ = std::max(depth_, depth);
    // Four parts: the cheapest split by the surface area heuristic, then each half's own.
    std::size_t cut[5] = {begin, 0, 0, 0, end};
    // Past sah_levels_ the medians, so that no world makes the tree deeper than the
    // query's stack allows.
    const bool balanced = depth >= sah_levels_;
    // One occluder (a world of one): alone in the first slot.
    cut[2] = end - begin >= 2 ? split_ids(bounds, ids, begin, end, balanced) : end;
    cut[1] = cut[2] - begin >= 2 ? split_ids(bounds, ids, begin, cut[2], balanced) : cut[2];
    cut[3] = end - cut[2] >= 2 ? split_ids(bounds, ids, cut[2], end, balanced) : end;
    for (int i = 0; i < 4; ++i) {
        const std::size_t lo = cut[i];
        const std::size_t hi = cut[i + 1];
        std::uint32_t child = kEmpty;
        Aabb box;
        if (hi > lo) {
            for (std::size_t k = lo; k < hi; ++k) {
                box.extend(bounds[ids[k]]);
            }
            // May grow nodes_: an index, not a reference, below.
            child = slot(bounds, ids, lo, hi, depth + 1);
            nodes_[index].used |= 1u << i;
        }
        nodes_[index].child[i] = child;
        for (int a = 0; a < 3; ++a) {
            nodes_[index].min[a][i] = box.min[a];
            nodes_[index].max[a][i] = box.max[a];
        }
    }
    return index;
}

} // namespace dsoc::visibility
