#include "dsoc/sim/reach_clipper.hpp"

#include <algorithm>
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
        if ((b.contents & (maps::contents_solid | maps::contents_player_clip)) == 0 ||
            b.bounds.is_empty()) {
            continue;
        }
        if (is_axial_box(b)) {
            boxes_.push_back(b.bounds);
        }
        // Faces a player can stand on that are not flat: walking down them needs no
        // gravity. The same test on the same normal as the mover's ground check
        // (player_move.cpp), so a face within a rounding error of flat counts.
        float steepest = 0.0f;
        for (const auto& p : b.planes) {
            if (p.normal.z >= move.min_walk_normal_z) {
                steepest = std::max(steepest, walk_down_speed(move, p.normal.z));
            }
        }
        if (steepest > 0.0f) {
            slopes_.push_back({b.bounds, steepest});
        }
    }
}

float ReachClipper::walk_down_speed_within(const visibility::Aabb& eye_region) const {
    // The player's box over the region, plus the ground probe and float slack.
    constexpr float kGroundReach = 1.0f;
    const visibility::Aabb swept{eye_region.min + box_min_ - glm::vec3(kGroundReach),
                                 eye_region.max + box_max_ + glm::vec3(kGroundReach)};
    float fastest = 0.0f;
    for (const Slope& s : slopes_) {
        if (s.bounds.min.x <= swept.max.x && s.bounds.max.x >= swept.min.x &&
            s.bounds.min.y <= swept.max.y && s.bounds.max.y >= swept.min.y &&
            s.bounds.min.z <= swept.max.z && s.bounds.max.z >= swept.min.z) {
            fastest = std::max(fastest, s.walk_down_speed);
        }
    }
    return fastest;
}

visibility::Aabb ReachClipper::clip(glm::vec3 eye, const visibility::Aabb& region,
                                    const visibility::EyeReach& reach) const {
    visibility::Aabb e = clip_to_walls(eye, region);
    if (reach.limits == nullptr || reach.limits->gravity <= 0.0f || reach.down_velocity < 0.0f) {
        return e;
    }
    // The region still holds every reachable eye, so the slopes near it are all the
    // slopes the player can stand on meanwhile.
    visibility::MotionLimits local = *reach.limits;
    local.fall_speed_floor = std::min(local.fall_speed_floor, walk_down_speed_within(e));
    const float floor = eye.z - (visibility::fall_bound(local, reach.seconds, reach.down_velocity) +
                                 local.fall_slack);
    e.min.z = std::min(std::max(e.min.z, floor), eye.z);
    return e;
}

visibility::Aabb ReachClipper::clip_to_walls(glm::vec3 eye, const visibility::Aabb& region) const {
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
