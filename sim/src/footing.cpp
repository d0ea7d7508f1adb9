#include "dsoc/sim/footing.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace dsoc::sim {

namespace {

/// How far below `start` the box dropped from there meets walkable ground within
/// `max_drop`, touching no hazard on the way; a negative depth when it meets none (or a
/// hazard); nullopt when it starts in solid. [Units: world units]
std::optional<float> safe_drop(const CollisionWorld& world, const MoveConfig& move, glm::vec3 start,
                               float max_drop, std::span<const maps::Hazard> hazards) {
    const BoxTrace down =
        world.trace_box(start, start - glm::vec3(0.0f, 0.0f, max_drop), move.mins, move.maxs);
    if (down.start_solid) {
        return std::nullopt;
    }
    if (down.fraction >= 1.0f || down.hit_normal.z < move.min_walk_normal_z) {
        return -1.0f; // nothing to land on within the drop, or ground too steep to stand on
    }
    const visibility::Aabb fall{down.end_position + move.mins, start + move.maxs};
    const bool into_hazard = std::ranges::any_of(
        hazards, [&](const maps::Hazard& h) { return h.bounds.overlaps(fall); });
    return into_hazard ? -1.0f : start.z - down.end_position.z;
}

/// safe_drop() from a step's height above `place`, so that stairs up do not start in
/// solid, or from `place` itself under a low ceiling; the depth below `place`.
std::optional<float> safe_drop_at(const CollisionWorld& world, const MoveConfig& move,
                                  glm::vec3 place, float max_drop,
                                  std::span<const maps::Hazard> hazards) {
    const glm::vec3 raised = place + glm::vec3(0.0f, 0.0f, move.step_height);
    if (auto depth = safe_drop(world, move, raised, move.step_height + max_drop, hazards)) {
        return *depth < 0.0f ? *depth : *depth - move.step_height;
    }
    return safe_drop(world, move, place, max_drop, hazards);
}

} // namespace

bool unsafe_ledge_ahead(const CollisionWorld& world, const MoveConfig& move, glm::vec3 position,
                        glm::vec3 direction, float speed, float lookahead, float max_drop,
                        std::span<const maps::Hazard> hazards) {
    const glm::vec3 flat(direction.x, direction.y, 0.0f);
    // Places along the way no further apart than half the box's width, so that a gap the
    // box fits into is not stepped over by the probes.
    const float spacing = 0.5f * std::min(move.maxs.x - move.mins.x, move.maxs.y - move.mins.y);
    const int probes = std::max(1, static_cast<int>(std::ceil(lookahead / spacing)));
    for (int k = 1; k <= probes; ++k) {
        const float ahead = lookahead * static_cast<float>(k) / static_cast<float>(probes);
        const glm::vec3 place = position + flat * ahead;
        const std::optional<float> depth = safe_drop_at(world, move, place, max_drop, hazards);
        if (!depth) {
            return false; // a wall or a higher step: movement deals with it, and with beyond
        }
        if (*depth < 0.0f) {
            return true;
        }
        if (*depth > move.step_height && move.gravity > 0.0f) {
            // Off the edge at `speed` it comes down further on, where the fall ends: there
            // must be footing too (a narrow ledge below is overshot).
            const float fall_seconds = std::sqrt(2.0f * *depth / move.gravity);
            const glm::vec3 landing = place + flat * (speed * fall_seconds);
            const std::optional<float> there =
                safe_drop_at(world, move, landing, max_drop, hazards);
            return there.has_value() && *there < 0.0f;
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
        if (safe_drop(world, move, placed.position, max_drop, hazards).value_or(-1.0f) >= 0.0f) {
            usable.push_back(spawn);
        }
    }
    if (usable.empty()) {
        usable.assign(spawns.begin(), spawns.end());
    }
    return usable;
}

} // namespace dsoc::sim
