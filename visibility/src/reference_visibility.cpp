#include "dsoc/visibility/reference_visibility.hpp"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace dsoc::visibility {

bool segment_blocked_by(glm::vec3 a, glm::vec3 b, std::span<const Plane> planes) {
    const glm::dvec3 da(a);
    const glm::dvec3 dir = glm::dvec3(b) - da;
    double t_enter = 0.0;
    double t_exit = 1.0;
    for (const Plane& p : planes) {
        const glm::dvec3 n(p.normal);
        const double start = glm::dot(n, da) - static_cast<double>(p.distance); // < 0 inside
        const double rate = glm::dot(n, dir);
        if (rate == 0.0) {
            if (start >= 0.0) {
                return false; // parallel and outside or on the plane: never strictly inside
            }
            continue;
        }
        const double t = -start / rate;
        if (rate < 0.0) {
            t_enter = std::max(t_enter, t);
        } else {
            t_exit = std::min(t_exit, t);
        }
        if (t_exit - t_enter <= 1.0e-6) {
            return false;
        }
    }
    return t_exit - t_enter > 1.0e-6;
}

bool ReferenceVisibility::segment_blocked(glm::vec3 eye, glm::vec3 point) const {
    Aabb segment_box;
    segment_box.extend(eye);
    segment_box.extend(point);
    for (OccluderId id = 0; id < world_->size(); ++id) {
        if (!world_->occluder(id).bounds().overlaps(segment_box)) {
            continue;
        }
        if (segment_blocked_by(eye, point, world_->solid_planes(id))) {
            return true;
        }
    }
    return false;
}

void ReferenceVisibility::box_samples(const Aabb& box, int grid, std::vector<glm::vec3>& out) {
    grid = std::max(grid, 2);
    const glm::vec3 size = box.size();
    out.push_back(box.center());
    for (int axis = 0; axis < 3; ++axis) {
        const int a1 = (axis + 1) % 3;
        const int a2 = (axis + 2) % 3;
        for (int side = 0; side < 2; ++side) {
            for (int i = 0; i < grid; ++i) {
                for (int j = 0; j < grid; ++j) {
                    glm::vec3 p;
                    p[axis] = side == 0 ? box.min[axis] : box.max[axis];
                    p[a1] = box.min[a1] +
                            size[a1] * static_cast<float>(i) / static_cast<float>(grid - 1);
                    p[a2] = box.min[a2] +
                            size[a2] * static_cast<float>(j) / static_cast<float>(grid - 1);
                    out.push_back(p);
                }
            }
        }
    }
}

Visibility ReferenceVisibility::test_box(glm::vec3 eye, const Aabb& box, int grid) const {
    if (box.contains(eye)) {
        return Visibility::visible;
    }
    // Occluders that can block any sample lie in the box spanned by eye and box.
    Aabb span = box;
    span.extend(eye);
    thread_local std::vector<OccluderId> candidates;
    thread_local std::vector<glm::vec3> samples;
    candidates.clear();
    samples.clear();
    for (OccluderId id = 0; id < world_->size(); ++id) {
        if (world_->occluder(id).bounds().overlaps(span)) {
            candidates.push_back(id);
        }
    }
    box_samples(box, grid, samples);
    for (const glm::vec3& p : samples) {
        bool blocked = false;
        for (const OccluderId id : candidates) {
            if (segment_blocked_by(eye, p, world_->solid_planes(id))) {
                blocked = true;
                break;
            }
        }
        if (!blocked) {
            return Visibility::visible;
        }
    }
    return Visibility::occluded;
}

} // namespace dsoc::visibility
