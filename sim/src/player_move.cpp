#include "dsoc/sim/player_move.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace dsoc::sim {
namespace {

constexpr float kOverclip = 1.001f;
constexpr int kMaxClipPlanes = 5;
constexpr int kMaxBumps = 4;
constexpr float kGroundProbe = 0.25f;
/// Quake 3 raises a spawned player this much above the spawn point's origin.
constexpr float kSpawnLift = 9.0f;

glm::vec3 clip_velocity(glm::vec3 v, glm::vec3 normal, float overbounce) {
    float backoff = glm::dot(v, normal);
    backoff = backoff < 0.0f ? backoff * overbounce : backoff / overbounce;
    return v - normal * backoff;
}

/// Enforces the speed contract on a velocity: horizontal speed <= max_speed, upward
/// <= jump_velocity, downward <= fall_cap (<= max_fall_speed). [Units: world units/s]
glm::vec3 clamp_velocity(glm::vec3 v, const MoveConfig& config, float fall_cap) {
    const float horizontal = std::sqrt(v.x * v.x + v.y * v.y);
    if (horizontal > config.max_speed) {
        const float scale = config.max_speed / horizontal;
        v.x *= scale;
        v.y *= scale;
    }
    v.z = std::clamp(v.z, -fall_cap, config.jump_velocity);
    return v;
}

class Mover {
public:
    /// `fall_cap`: the most downward speed any velocity of this move may have.
    Mover(const CollisionWorld& world, const MoveConfig& config, MoveState& state, float fall_cap)
        : world_(world), config_(config), state_(state), fall_cap_(fall_cap) {}

    void set_fall_cap(float fall_cap) { fall_cap_ = fall_cap; }
    [[nodiscard]] glm::vec3 clamp(glm::vec3 v) const {
        return clamp_velocity(v, config_, fall_cap_);
    }

    void ground_check();
    /// Moves along the velocity for `dt`, sliding along what it hits. Returns true
    /// when something was hit.
    bool slide(float dt);
    /// On the ground: slide, and if blocked, try again from up to min(step_height,
    /// climb_budget) higher; the step is kept only when the move rises at most
    /// climb_budget in all. [Units: world units]
    void step_slide(float dt, float climb_budget);
    BoxTrace trace(glm::vec3 from, glm::vec3 to) const {
        return world_.trace_box(from, to, config_.mins, config_.maxs);
    }

private:
    const CollisionWorld& world_;
    const MoveConfig& config_;
    MoveState& state_;
    float fall_cap_;
};

void Mover::ground_check() {
    const glm::vec3 below = state_.position - glm::vec3(0.0f, 0.0f, kGroundProbe);
    const BoxTrace down = trace(state_.position, below);
    if (down.fraction >= 1.0f || down.all_solid) {
        state_.on_ground = false;
        return;
    }
    // Moving up and away from the ground (a jump): not on it.
    if (state_.velocity.z > 0.0f && glm::dot(state_.velocity, down.hit_normal) > 10.0f) {
        state_.on_ground = false;
        return;
    }
    if (down.hit_normal.z < config_.min_walk_normal_z) {
        state_.on_ground = false; // too steep: slide down it
        return;
    }
    state_.on_ground = true;
    state_.ground_normal = down.hit_normal;
    if (state_.velocity.z < 0.0f) {
        state_.velocity.z = 0.0f; // landed
    }
}

bool Mover::slide(float dt) {
    std::array<glm::vec3, kMaxClipPlanes> planes{};
    int plane_count = 0;
    if (state_.on_ground) {
        planes[plane_count++] = state_.ground_normal;
    }
    const float speed = glm::length(state_.velocity);
    if (speed > 0.0f) {
        planes[plane_count++] = state_.velocity / speed; // never turn back
    }
    float time_left = dt;
    int bump = 0;
    for (; bump < kMaxBumps; ++bump) {
        const glm::vec3 end = state_.position + state_.velocity * time_left;
        const BoxTrace hit = trace(state_.position, end);
        if (hit.all_solid) {
            state_.velocity.z = 0.0f; // trapped: do not move at all
            return true;
        }
        if (hit.fraction > 0.0f) {
            state_.position = hit.end_position;
        }
        if (hit.fraction >= 1.0f) {
            break;
        }
        time_left -= time_left * hit.fraction;
        if (plane_count >= kMaxClipPlanes) {
            state_.velocity = glm::vec3(0.0f);
            return true;
        }
        // The same plane again: nudge the velocity out along it.
        bool seen = false;
        for (int i = 0; i < plane_count && !seen; ++i) {
            if (glm::dot(hit.hit_normal, planes[static_cast<std::size_t>(i)]) > 0.99f) {
                state_.velocity = clamp(state_.velocity + hit.hit_normal);
                seen = true;
            }
        }
        if (seen) {
            continue;
        }
        planes[static_cast<std::size_t>(plane_count++)] = hit.hit_normal;
        // Make the velocity parallel to every plane it runs into.
        for (int i = 0; i < plane_count; ++i) {
            const glm::vec3 pi = planes[static_cast<std::size_t>(i)];
            if (glm::dot(state_.velocity, pi) >= 0.1f) {
                continue;
            }
            glm::vec3 clipped = clip_velocity(state_.velocity, pi, kOverclip);
            bool stopped = false;
            for (int j = 0; j < plane_count && !stopped; ++j) {
                const glm::vec3 pj = planes[static_cast<std::size_t>(j)];
                if (j == i || glm::dot(clipped, pj) >= 0.1f) {
                    continue;
                }
                clipped = clip_velocity(clipped, pj, kOverclip);
                if (glm::dot(clipped, pi) >= 0.0f) {
                    continue;
                }
                // Into two planes: slide along their crease.
                const glm::vec3 crease = glm::cross(pi, pj);
                const float crease_length = glm::length(crease);
                if (crease_length < 1e-6f) {
                    stopped = true;
                    break;
                }
                const glm::vec3 dir = crease / crease_length;
                clipped = dir * glm::dot(dir, state_.velocity);
                for (int k = 0; k < plane_count; ++k) {
                    if (k != i && k != j &&
                        glm::dot(clipped, planes[static_cast<std::size_t>(k)]) < 0.1f) {
                        stopped = true; // into three planes: stop dead
                        break;
                    }
                }
            }
            state_.velocity = stopped ? glm::vec3(0.0f) : clamp(clipped);
            break;
        }
        if (state_.velocity == glm::vec3(0.0f)) {
            return true;
        }
    }
    return bump != 0;
}

void Mover::step_slide(float dt, float climb_budget) {
    const glm::vec3 start_position = state_.position;
    const glm::vec3 start_velocity = state_.velocity;
    const float step_limit = std::min(config_.step_height, climb_budget);
    if (!slide(dt) || step_limit <= 0.0f) {
        return; // moved the whole way (or no credit to step with)
    }
    const glm::vec3 slid_position = state_.position;
    const glm::vec3 slid_velocity = state_.velocity;
    auto keep_plain_slide = [&] {
        state_.position = slid_position;
        state_.velocity = slid_velocity;
    };
    // Rise by at most the step limit, slide from there, settle back down.
    const BoxTrace up = trace(start_position, start_position + glm::vec3(0, 0, step_limit));
    if (up.all_solid || up.start_solid) {
        return;
    }
    const float rise = up.end_position.z - start_position.z;
    if (rise <= 0.0f) {
        return;
    }
    state_.position = up.end_position;
    state_.velocity = start_velocity;
    slide(dt);
    const BoxTrace down = trace(state_.position, state_.position - glm::vec3(0, 0, rise));
    if (down.all_solid) {
        keep_plain_slide();
        return;
    }
    state_.position = down.end_position;
    if (down.fraction < 1.0f) {
        state_.velocity = clamp(clip_velocity(state_.velocity, down.hit_normal, kOverclip));
    }
    // Keep the step only if it got further than the plain slide did, and only if the
    // whole move's rise (the step plus what the velocity climbed) fits the budget.
    const glm::vec2 stepped(state_.position.x - start_position.x,
                            state_.position.y - start_position.y);
    const glm::vec2 plain(slid_position.x - start_position.x, slid_position.y - start_position.y);
    if (glm::dot(stepped, stepped) <= glm::dot(plain, plain) + 1e-3f ||
        state_.position.z - start_position.z > climb_budget) {
        keep_plain_slide();
    }
}

void accelerate(glm::vec3& velocity, glm::vec3 wish_direction, float wish_speed, float accel,
                float dt) {
    const float current = glm::dot(velocity, wish_direction);
    const float add = wish_speed - current;
    if (add <= 0.0f) {
        return;
    }
    velocity += std::min(accel * dt * wish_speed, add) * wish_direction;
}

/// One move of `dt` seconds whose rise may not exceed `climb_budget`: a jump or a
/// ramp rises at most jump_velocity * dt <= climb_rate * dt <= climb_budget through
/// the velocity, and step_slide() keeps a step only when the move's rise fits.
void move_within(const CollisionWorld& world, const MoveConfig& config, const MoveInput& input,
                 float dt, float climb_budget, MoveState& state) {
    const float start_down_speed = std::max(0.0f, -state.velocity.z);
    Mover mover(world, config, state, config.max_fall_speed);
    mover.ground_check();

    glm::vec3 wish(input.wish_direction.x, input.wish_direction.y, 0.0f);
    const float wish_length = glm::length(wish);
    wish = wish_length > 1e-6f ? wish / wish_length : glm::vec3(0.0f);
    const float wish_speed = wish_length > 1e-6f ? config.max_speed : 0.0f;

    bool jumped = false;
    if (state.on_ground && input.jump) {
        state.velocity.z = config.jump_velocity;
        state.on_ground = false;
        jumped = true;
    }
    // The fall contract (player_move.hpp): this move's downward speed is at most
    // gravity * dt more than the larger of where it was and, on walkable ground, what
    // walking down that ground gives.
    const float ground_speed =
        state.on_ground ? walk_down_speed(config, state.ground_normal.z) : 0.0f;
    mover.set_fall_cap(std::min(config.max_fall_speed,
                                std::max(start_down_speed, ground_speed) + config.gravity * dt));
    if (state.on_ground) {
        // Friction, then acceleration along the ground.
        const float speed = glm::length(state.velocity);
        if (speed > 0.0f) {
            const float drop = std::max(speed, config.stop_speed) * config.friction * dt;
            state.velocity *= std::max(0.0f, speed - drop) / speed;
        }
        accelerate(state.velocity, wish, wish_speed, config.ground_accelerate, dt);
        const float speed_after = glm::length(state.velocity);
        state.velocity = clip_velocity(state.velocity, state.ground_normal, kOverclip);
        const float clipped_speed = glm::length(state.velocity);
        if (clipped_speed > 0.0f) {
            state.velocity *= speed_after / clipped_speed; // keep speed on slopes
        }
        state.velocity = mover.clamp(state.velocity);
        if (state.velocity.x == 0.0f && state.velocity.y == 0.0f) {
            state.velocity.z = 0.0f;
            mover.ground_check();
            return;
        }
        mover.step_slide(dt, climb_budget);
    } else {
        accelerate(state.velocity, wish, wish_speed, config.air_accelerate, dt);
        if (!jumped) {
            state.velocity.z -= config.gravity * dt;
        }
        state.velocity = mover.clamp(state.velocity);
        mover.slide(dt);
    }
    mover.ground_check();
}

} // namespace

std::vector<std::string> validate(const MoveConfig& c) {
    std::vector<std::string> problems;
    auto require = [&](bool ok, const char* what) {
        if (!ok) {
            problems.emplace_back(what);
        }
    };
    require(c.max_speed > 0.0f, "max_speed must be > 0");
    require(c.gravity >= 0.0f, "gravity must be >= 0");
    require(c.jump_velocity >= 0.0f, "jump_velocity must be >= 0");
    require(c.max_fall_speed > 0.0f, "max_fall_speed must be > 0");
    require(c.step_height >= 0.0f, "step_height must be >= 0");
    require(c.climb_rate >= c.jump_velocity,
            "climb_rate must be >= jump_velocity (a jump's rise is paid from the climb credit)");
    require(c.ground_accelerate >= 0.0f && c.air_accelerate >= 0.0f,
            "ground_accelerate and air_accelerate must be >= 0");
    require(c.friction >= 0.0f && c.stop_speed >= 0.0f, "friction and stop_speed must be >= 0");
    require(c.min_walk_normal_z >= 0.0f && c.min_walk_normal_z <= 1.0f,
            "min_walk_normal_z must be in 0..1");
    require(c.mins.x < c.maxs.x && c.mins.y < c.maxs.y && c.mins.z < c.maxs.z,
            "mins must be below maxs on every axis");
    return problems;
}

float walk_down_speed(const MoveConfig& config, float normal_z) {
    const float n = std::clamp(normal_z, 0.0f, 1.0f);
    return config.max_speed * std::sqrt(1.0f - n * n);
}

MotionBound motion_bound(const MoveConfig& config, float seconds) {
    const float t = std::max(0.0f, seconds);
    return {config.max_speed * t, config.climb_rate * t + config.step_height,
            config.max_fall_speed * t};
}

void player_move(const CollisionWorld& world, const MoveConfig& config, const MoveInput& input,
                 float dt, MoveState& state) {
    if (!(dt > 0.0f)) {
        return;
    }
    // Every way up (a jump, a ramp, a step) is paid from one budget: the credit left
    // by earlier moves plus climb_rate * dt. What the move does not use is kept, up to
    // step_height, so the rise over any run of moves is at most
    // step_height + climb_rate * (their total time).
    const float climb_budget = state.climb_credit + config.climb_rate * dt;
    const float start_z = state.position.z;
    move_within(world, config, input, dt, climb_budget, state);
    const float rise = std::max(0.0f, state.position.z - start_z);
    state.climb_credit = std::clamp(climb_budget - rise, 0.0f, config.step_height);
}

bool touches_hazard(const MoveConfig& config, const MoveState& state,
                    std::span<const maps::Hazard> hazards) {
    const visibility::Aabb box{state.position + config.mins, state.position + config.maxs};
    return std::ranges::any_of(hazards,
                               [&](const maps::Hazard& h) { return h.bounds.overlaps(box); });
}

MoveState spawn_state(const CollisionWorld& world, const MoveConfig& config,
                      glm::vec3 spawn_origin) {
    MoveState state;
    state.position = spawn_origin + glm::vec3(0.0f, 0.0f, kSpawnLift);
    if (world.box_in_solid(state.position, config.mins, config.maxs)) {
        state.position = spawn_origin; // a low ceiling: stay where the mapper put it
    }
    state.climb_credit = config.step_height;
    Mover(world, config, state, config.max_fall_speed).ground_check();
    return state;
}

} // namespace dsoc::sim
