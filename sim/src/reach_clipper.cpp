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

ReachClipper::ReachClipper(std::span<const maps::CollisionBrush> brushes, const MoveConfig& move,
                           float column_size)
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
    index_boxes(column_size);
}

void ReachClipper::index_boxes(float column_size) {
    if (boxes_.empty()) {
        return;
    }
    visibility::Aabb all = boxes_.front();
    for (const auto& k : boxes_) {
        all.extend(k);
    }
    columns_origin_ = {all.min.x, all.min.y};
    const glm::vec2 size{all.max.x - all.min.x, all.max.y - all.min.y};
    column_size_ =
        std::max({column_size, size.x / kMaxColumnsPerAxis, size.y / kMaxColumnsPerAxis});
    columns_x_ = static_cast<int>(size.x / column_size_) + 1;
    columns_y_ = static_cast<int>(size.y / column_size_) + 1;
    // Two passes over the boxes: count per column, then fill (CSR).
    column_start_.assign(static_cast<std::size_t>(columns_x_ * columns_y_) + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<std::uint32_t> next(column_start_.begin(), column_start_.end() - 1);
        for (std::uint32_t i = 0; i < boxes_.size(); ++i) {
            const ColumnRange r = columns_of(boxes_[i]);
            for (int y = r.y0; y <= r.y1; ++y) {
                for (int x = r.x0; x <= r.x1; ++x) {
                    const auto col = static_cast<std::size_t>(y * columns_x_ + x);
                    if (pass == 0) {
                        ++column_start_[col + 1];
                    } else {
                        column_boxes_[next[col]++] = i;
                    }
                }
            }
        }
        if (pass == 0) {
            for (std::size_t c = 1; c < column_start_.size(); ++c) {
                column_start_[c] += column_start_[c - 1];
            }
            column_boxes_.resize(column_start_.back());
        }
    }
}

ReachClipper::ColumnRange ReachClipper::columns_of(const visibility::Aabb& area) const {
    const auto column = [&](float v, float origin, int count) {
        const float c = std::floor((v - origin) / column_size_);
        if (!(c >= 0.0f)) { // below the grid, or NaN
            return 0;
        }
        return c >= static_cast<float>(count - 1) ? count - 1 : static_cast<int>(c);
    };
    return {column(area.min.x, columns_origin_.x, columns_x_),
            column(area.max.x, columns_origin_.x, columns_x_),
            column(area.min.y, columns_origin_.y, columns_y_),
            column(area.max.y, columns_origin_.y, columns_y_)};
}

template <class Visit>
void ReachClipper::for_boxes_near(const visibility::Aabb& area, Visit&& visit) const {
    if (boxes_.empty()) {
        return;
    }
    const ColumnRange r = columns_of(area);
    for (int y = r.y0; y <= r.y1; ++y) {
        for (int x = r.x0; x <= r.x1; ++x) {
            const auto col = static_cast<std::size_t>(y * columns_x_ + x);
            for (std::uint32_t k = column_start_[col]; k < column_start_[col + 1]; ++k) {
                visit(boxes_[column_boxes_[k]]);
            }
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
        bool stuck = false;
        // Every box's clip is a min or a max against the same swept region, so the order
        // of the boxes, and a box seen twice, change nothing.
        for_boxes_near(swept, [&](const visibility::Aabb& k) {
            if (!(k.min.x < swept.max.x && k.max.x > swept.min.x && k.min.y < swept.max.y &&
                  k.max.y > swept.min.y && k.min.z < swept.max.z && k.max.z > swept.min.z)) {
                return;
            }
            if (player.min.x < k.max.x && player.max.x > k.min.x && player.min.y < k.max.y &&
                player.max.y > k.min.y && player.min.z < k.max.z && player.max.z > k.min.z) {
                stuck = true;
                return;
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
        });
        if (stuck) {
            return region; // stuck inside a brush: promise nothing extra
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
