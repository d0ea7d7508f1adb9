#include "dsoc/visibility/occluder_merge.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::visibility {

namespace {

/// True when every face of the polyhedron lies on a plane with an axial normal.
bool is_axial_box(const ConvexPolyhedron& p) {
    if (p.is_empty() || p.faces().size() != 6) {
        return false;
    }
    for (const auto& f : p.faces()) {
        const glm::vec3 n = glm::abs(f.plane.normal);
        if (std::max({n.x, n.y, n.z}) < 1.0f - 1e-5f) {
            return false;
        }
    }
    return true;
}

/// One pass along `axis`: boxes with the same cross-section on the other two axes
/// that touch or overlap along `axis` become one. Returns true when something merged.
bool merge_along(std::vector<Aabb>& boxes, int axis, float tol) {
    const int b = (axis + 1) % 3;
    const int c = (axis + 2) % 3;
    std::sort(boxes.begin(), boxes.end(), [&](const Aabb& l, const Aabb& r) {
        // Group by cross-section (rounded to the tolerance), then along the axis.
        const auto key = [&](const Aabb& x) {
            return std::array<long, 4>{std::lround(x.min[b] / tol), std::lround(x.max[b] / tol),
                                       std::lround(x.min[c] / tol), std::lround(x.max[c] / tol)};
        };
        const auto kl = key(l);
        const auto kr = key(r);
        if (kl != kr) {
            return kl < kr;
        }
        return l.min[axis] < r.min[axis];
    });
    std::vector<Aabb> out;
    out.reserve(boxes.size());
    bool merged = false;
    for (const Aabb& box : boxes) {
        if (!out.empty()) {
            Aabb& last = out.back();
            const bool same_section = std::abs(last.min[b] - box.min[b]) <= tol &&
                                      std::abs(last.max[b] - box.max[b]) <= tol &&
                                      std::abs(last.min[c] - box.min[c]) <= tol &&
                                      std::abs(last.max[c] - box.max[c]) <= tol;
            if (same_section && box.min[axis] <= last.max[axis] + tol) {
                // The union is a box; keep the inner cross-section so a tolerance
                // never makes the merged box bigger than the solid.
                last.min[b] = std::max(last.min[b], box.min[b]);
                last.max[b] = std::min(last.max[b], box.max[b]);
                last.min[c] = std::max(last.min[c], box.min[c]);
                last.max[c] = std::min(last.max[c], box.max[c]);
                last.max[axis] = std::max(last.max[axis], box.max[axis]);
                merged = true;
                continue;
            }
        }
        out.push_back(box);
    }
    boxes.swap(out);
    return merged;
}

} // namespace

std::vector<ConvexPolyhedron> merge_box_occluders(const std::vector<ConvexPolyhedron>& occluders,
                                                  OccluderMergeStats* stats, float tolerance) {
    std::vector<ConvexPolyhedron> out;
    std::vector<Aabb> boxes;
    for (const auto& o : occluders) {
        if (is_axial_box(o)) {
            boxes.push_back(o.bounds());
        } else if (!o.is_empty()) {
            out.push_back(o);
        }
    }
    const std::size_t box_count = boxes.size();
    for (int round = 0; round < 8; ++round) {
        bool any = false;
        for (int axis = 0; axis < 3; ++axis) {
            any = merge_along(boxes, axis, tolerance) || any;
        }
        if (!any) {
            break;
        }
    }
    for (const Aabb& box : boxes) {
        out.push_back(ConvexPolyhedron::from_aabb(box));
    }
    if (stats != nullptr) {
        stats->input = occluders.size();
        stats->boxes = box_count;
        stats->output = out.size();
    }
    return out;
}

} // namespace dsoc::visibility
