#include "dsoc/sim/reach_clipper.hpp"

#include <cmath>

namespace dsoc::sim {

namespace {

/// A brush is an axis-aligned box when every plane is axial and sits on its bounds.
bool is_axial_box(const maps::CollisionBrush& brush) {
    constexpr float kEps = 1e-3f;
    for (const auto& p : brush.planes) {
        const glm::vec3 n = p.normal;
        int axis = -1;
        for (int a = 0; a < 3; ++a) {
            if (std::abs(std::abs(n[a]) - 1.0f) < kEps) {
                axis = a;
            }
        }
        if (axis < 0) {
            return false;
        }
        const float on_bounds = n[axis] > 0.0f ? brush.bounds.max[axis] : -brush.bounds.min[axis];
        if (std::abs(p.distance - on_bounds) > 0.01f) {
            return false;
        }
    }
    return true;
}

} // namespace

ReachClipper::ReachClipper(std::span<const maps::CollisionBrush> brushes, const MoveConfig& move)
    : box_min_(move.mins - glm::vec3(0.0f, 0.0f, move.eye_height)),
      box_max_(move.maxs - glm::vec3(0.0f, 0.0f, move.eye_height)) {
    for (const auto& b : brushes) {
        if ((b.contents & (maps::contents_solid | maps::contents_player_clip)) != 0 &&
            !b.bounds.is_empty() && is_axial_box(b)) {
            boxes_.push_back(b.bounds);
        }
    }
}

visibility::Aabb ReachClipper::clip(glm::vec3 eye, const visibility::Aabb& region) const {
    const visibility::Aabb player{eye + box_min_, eye + box_max_};
    visibility::Aabb e = region;
    // Each pass can only shrink e; a few passes reach the fixed point in practice.
    for (int pass = 0; pass < 3; ++pass) {
        bool changed = false;
        const visibility::Aabb swept{e.min + box_min_, e.max + box_max_};
        for (const auto& k : boxes_) {
            if (!(k.min.x < swept.max.x && k.max.x > swept.min.x && k.min.y < swept.max.y &&
                  k.max.y > swept.min.y && k.min.z < swept.max.z && k.max.z > swept.min.z)) {
                continue;
            }
            if (player.min.x < k.max.x && player.max.x > k.min.x && player.min.y < k.max.y &&
                player.max.y > k.min.y && player.min.z < k.max.z && player.max.z > k.min.z) {
                return region; // stuck inside a brush: promise nothing extra
            }
            for (int a = 0; a < 3; ++a) {
                const int b = (a + 1) % 3;
                const int c = (a + 2) % 3;
                // The face must cover the swept region's whole cross-section.
                if (k.min[b] > swept.min[b] || k.max[b] < swept.max[b] || k.min[c] > swept.min[c] ||
                    k.max[c] < swept.max[c]) {
                    continue;
                }
                if (player.max[a] <= k.min[a]) { // brush ahead on +a
                    const float limit = k.min[a] - box_max_[a];
                    if (limit < e.max[a]) {
                        e.max[a] = limit;
                        changed = true;
                    }
                } else if (player.min[a] >= k.max[a]) { // brush behind on -a
                    const float limit = k.max[a] - box_min_[a];
                    if (limit > e.min[a]) {
                        e.min[a] = limit;
                        changed = true;
                    }
                }
            }
        }
        if (!changed) {
            break;
        }
    }
    // Never clip past the eye itself (float noise when touching a face).
    e.min = glm::min(e.min, eye);
    e.max = glm::max(e.max, eye);
    return e;
}

} // namespace dsoc::sim
