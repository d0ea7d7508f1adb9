#include "dsoc/sim/player_space.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::sim {

maps::PlayerSpace player_space(const MoveConfig& move, float reach_seconds) {
    // Without gravity a jump has no apex: the limit of the settings' range answers.
    constexpr float kHighest = 4096.0f;
    const float apex = move.gravity > 0.0f
                           ? move.jump_velocity * move.jump_velocity / (2.0f * move.gravity)
                           : kHighest;
    const MotionBound reach = motion_bound(move, reach_seconds);
    const float origin = -move.mins.z; // above the ground where the box stands
    const float raised = origin + apex + move.step_height;
    const float box_top = raised + move.maxs.z;
    const float eye_region_top = raised + move.eye_height + reach.up;
    const float half_width = std::max({move.maxs.x, -move.mins.x, move.maxs.y, -move.mins.y});
    maps::PlayerSpace space;
    space.min_walk_normal_z = move.min_walk_normal_z;
    space.height = std::min(kHighest, std::max(box_top, eye_region_top));
    space.margin = std::min(kHighest, reach.horizontal + half_width);
    return space;
}

} // namespace dsoc::sim
