#include "dsoc/sim/footing.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace dsoc::sim {

namespace {

/// Whether the box dropped from `start` meets walkable ground within `max_drop` below without
/// touching a hazard on the way; nullopt when it starts in solid.
std::optional<bool> lands_safely(const CollisionWorld& world, const MoveConfig& move,
                                 glm::vec3 start, float max_drop,
                                 std::span<const maps::Hazard> hazards) {
    const BoxTrace down =
        world.trace_box(start, start - glm::vec3(0.0f, 0.0f, max_drop), move.mins, move.maxs);
    if (down.start_solid) {
        return std::nullopt;
    }
    if (down.fraction >= 1.0f || down.hit_normal.z < move.min_walk_normal_z) {
        return false; // nothing to land on within the drop, or ground too steep to stand on
    }
    const visibility::Aabb fall{down.end_position + move.mins, start + move.maxs};
    return std::ranges::none_of(hazards,
                                [&](const maps::Hazard& h) { return h.bounds.overlaps(fall); });
}

} // namespace

bool unsafe_ledge_ahead(const CollisionWorld& world, const MoveConfig& move, glm::vec3 position,
                        glm::vec3 direction, float lookahead, float max_drop,
                        std::span<const maps::Hazard> hazards) {
    const glm::vec3 flat(direction.x, direction.y, 0.0f);
    // Places along the way no further apart than half the box's width, so that a gap the
    // box fits into is not stepped over by the probes.
    const float spacing = 0.5f * std::min(move.maxs.x - move.mins.x, move.maxs.y - move.mins.y);
    const int probes = std::max(1, static_cast<int>(std::ceil(lookahead / spacing)));
    for (int k = 1; k <= probes; ++k) {
        const float ahead = lookahead * static_cast<float>(k) / static_cast<float>(probes);
        // From a step's height above the place, so that stairs up do not start in solid;
        // down a step and the drop from there.
        const glm::vec3 start = position + flat * ahead + glm::vec3(0.0f, 0.0f, move.step_height);
        const std::optional<bool> safe =
            lands_safely(world, move, start, move.step_height + max_drop, hazards);
        if (!safe) {
            return false; // a wall or a higher step: movement deals with it, and with beyond
        }
        if (!*safe) {
            return true;
        }
    }
    return false;
}

std::vector<maps::SpawnPoint> spawn_points_with_footing(const CollisionWorld& world,
                                                        const MoveConfig& move,
                                                        std::span<const maps::SpawnPoint> spawns,
                                                        float max_drop,
                                                        std::span<const maps::Hazard> hazards) {
    std::vector<maps::SpawnPoint> usable;
    for (const maps::SpawnPoint& spawn : spawns) {
        const MoveState placed = spawn_state(world, move, spawn.origin);
        if (lands_safely(world, move, placed.position, max_drop, hazards).value_or(false)) {
            usable.push_back(spawn);
        }
    }
    if (usable.empty()) {
        usable.assign(spawns.begin(), spawns.end());
    }
    return usable;
}

} // namespace dsoc::sim
