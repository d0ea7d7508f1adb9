#include "dsoc/sim/shots.hpp"

#include <glm/trigonometric.hpp>

#include <cmath>

namespace dsoc::sim {

glm::vec3 view_direction(float yaw_deg, float pitch_deg) {
    const float yaw = glm::radians(yaw_deg);
    const float pitch = glm::radians(pitch_deg);
    return {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), -std::sin(pitch)};
}

std::optional<std::size_t> first_hit(const CollisionWorld& world, glm::vec3 eye,
                                     glm::vec3 direction, float range,
                                     std::span<const visibility::Aabb> boxes,
                                     std::span<const std::uint8_t> hittable, std::size_t shooter) {
    // The nearest box on the line first (cheap), then walls only that far: when a wall
    // stands before it, every farther box is behind that wall too. The parameter runs
    // over [0, range] (direction is a unit vector).
    const glm::vec3 inv = 1.0f / direction;
    float nearest = range;
    std::optional<std::size_t> hit;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        if (i == shooter || hittable[i] == 0) {
            continue;
        }
        float t0 = 0.0f;
        float t1 = nearest;
        if (visibility::clip_segment_to_box(eye, inv, boxes[i], t0, t1) && t0 < nearest) {
            nearest = t0;
            hit = i;
        }
    }
    if (!hit) {
        return std::nullopt;
    }
    const BoxTrace wall =
        world.trace_box(eye, eye + direction * nearest, glm::vec3(0.0f), glm::vec3(0.0f));
    if (wall.start_solid || wall.fraction < 1.0f) {
        return std::nullopt; // the muzzle is inside a wall, or a wall stands before the box
    }
    return hit;
}

} // namespace dsoc::sim
