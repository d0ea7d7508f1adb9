#include "dsoc/visibility/tbv.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::visibility {

float fall_bound(const MotionLimits& limits, float seconds, float down_velocity) {
    float fall = limits.down_speed * seconds;
    if (limits.gravity > 0.0f && down_velocity >= 0.0f) {
        const float start_speed =
            std::max(down_velocity, limits.fall_speed_floor) + limits.fall_speed_margin;
        fall = std::min(fall, start_speed * seconds + 0.5f * limits.gravity * seconds * seconds);
    }
    return fall;
}

Aabb reachable_box(const Aabb& box, const MotionLimits& limits, float seconds, float expansion,
                   float down_velocity) {
    const float h = limits.horizontal_speed * seconds * expansion;
    const float fall = fall_bound(limits, seconds, down_velocity);
    Aabb out = box;
    out.min.x -= h;
    out.min.y -= h;
    out.max.x += h;
    out.max.y += h;
    out.min.z -= (fall + limits.fall_slack) * expansion;
    out.max.z += (limits.up_speed * seconds + limits.vertical_slack) * expansion;
    return out;
}

bool within_reach(glm::vec3 from, glm::vec3 to, const MotionLimits& limits, float seconds,
                  float tolerance) {
    const glm::vec3 d = to - from;
    const float h = limits.horizontal_speed * seconds + tolerance;
    if (d.x * d.x + d.y * d.y > h * h) {
        return false;
    }
    if (d.z > limits.up_speed * seconds + limits.vertical_slack + tolerance) {
        return false;
    }
    return -d.z <= limits.down_speed * seconds + limits.fall_slack + tolerance;
}

void MovementHistory::push(glm::vec3 center) {
    samples_[static_cast<std::size_t>(head_)] = center;
    head_ = (head_ + 1) % kCapacity;
    count_ = std::min(count_ + 1, kCapacity);
}

glm::vec3 MovementHistory::at(int i) const {
    const int oldest = (head_ - count_ + kCapacity) % kCapacity;
    return samples_[static_cast<std::size_t>((oldest + i) % kCapacity)];
}

namespace {

/// Two-sided normal quantile for a confidence level (Acklam-free, table + lerp:
/// accurate to a few percent, which is all a heuristic needs).
float z_for_confidence(float confidence) {
    static constexpr float kLevels[] = {0.5f, 0.8f, 0.9f, 0.95f, 0.99f, 0.999f};
    static constexpr float kZ[] = {0.674f, 1.282f, 1.645f, 1.960f, 2.576f, 3.291f};
    const float c = std::clamp(confidence, kLevels[0], kLevels[5]);
    for (int i = 1; i < 6; ++i) {
        if (c <= kLevels[i]) {
            const float t = (c - kLevels[i - 1]) / (kLevels[i] - kLevels[i - 1]);
            return kZ[i - 1] + t * (kZ[i] - kZ[i - 1]);
        }
    }
    return kZ[5];
}

} // namespace

Aabb fuzzy_box(const Aabb& box, const MovementHistory& history, int ticks, float tick_seconds,
               float confidence, const MotionLimits& limits) {
    const int n = history.size();
    if (n < 2) {
        return reachable_box(box, limits, static_cast<float>(ticks) * tick_seconds);
    }
    const glm::vec3 first = history.at(0);
    const glm::vec3 last = history.at(n - 1);
    const glm::vec3 velocity = (last - first) / static_cast<float>(n - 1); // per tick
    // Residual spread of the samples around the straight line through them.
    glm::vec3 sum_sq{0.0f};
    for (int i = 0; i < n; ++i) {
        const glm::vec3 predicted = first + velocity * static_cast<float>(i);
        const glm::vec3 r = history.at(i) - predicted;
        sum_sq += r * r;
    }
    const glm::vec3 sigma = glm::sqrt(sum_sq / static_cast<float>(n)) + glm::vec3(1.0f);
    const float z = z_for_confidence(confidence);
    // A turn is the main risk: the per-tick speed can rotate. Allow a lateral spread
    // that grows with the speed, scaled by the same z.
    const float speed = std::sqrt(velocity.x * velocity.x + velocity.y * velocity.y);
    Aabb out = box;
    const glm::vec3 half = box.half_extents();
    for (int t = 1; t <= ticks; ++t) {
        const float ft = static_cast<float>(t);
        const glm::vec3 center = box.center() + velocity * ft;
        glm::vec3 spread = sigma * z * std::sqrt(ft);
        spread.x += 0.25f * z * speed * ft;
        spread.y += 0.25f * z * speed * ft;
        out.extend(Aabb{center - half - spread, center + half + spread});
    }
    // Never larger than the conservative box: past that, prediction is pointless.
    const Aabb bound = reachable_box(box, limits, static_cast<float>(ticks) * tick_seconds);
    out.min = glm::max(out.min, bound.min);
    out.max = glm::min(out.max, bound.max);
    return out;
}

} // namespace dsoc::visibility
