#include "dsoc/sim/wander_bot.hpp"

#include "dsoc/sim/footing.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace dsoc::sim {
namespace {

std::uint64_t next_random(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

float random_unit(std::uint64_t& state) {
    return static_cast<float>(next_random(state) >> 40) * (1.0f / 16777216.0f);
}

float horizontal_distance(glm::vec3 a, glm::vec3 b) {
    return std::hypot(a.x - b.x, a.y - b.y);
}

void pick_goal(WanderBot& bot, const WanderConfig& config,
               std::span<const maps::SpawnPoint> spawns) {
    const bool use_spawn =
        bot.remembered.empty() || random_unit(bot.random_state) < config.spawn_goal_chance;
    if (use_spawn && !spawns.empty()) {
        bot.goal = spawns[next_random(bot.random_state) % spawns.size()].origin;
    } else if (!bot.remembered.empty()) {
        bot.goal = bot.remembered[next_random(bot.random_state) % bot.remembered.size()];
    }
    bot.best_goal_distance = horizontal_distance(bot.state.position, bot.goal);
    bot.since_progress = 0.0f;
}

/// Whether `input`, given on the ground, takes the bot off a ledge it should not walk
/// off: on its way ahead, where it slides while it turns, or, for a jump, where it comes
/// down at full speed or a ledge beside or behind it.
bool leads_off_a_ledge(const WanderBot& bot, const CollisionWorld& world,
                       const WanderConfig& config, const MoveConfig& move, const MoveInput& input,
                       std::span<const maps::Hazard> hazards) {
    // Off an edge it carries on at full speed at the most.
    const auto unsafe_along = [&](glm::vec3 direction, float lookahead) {
        return unsafe_ledge_ahead(world, move, bot.state.position, direction, move.max_speed,
                                  lookahead, config.max_safe_drop, hazards);
    };
    if (unsafe_along(input.wish_direction, config.ledge_lookahead)) {
        return true;
    }
    const glm::vec3 sliding(bot.state.velocity.x, bot.state.velocity.y, 0.0f);
    const float speed = glm::length(sliding);
    // Turning by more than about 25 degrees: the slide goes elsewhere for a while.
    if (speed > move.stop_speed && glm::dot(sliding / speed, input.wish_direction) < 0.9f &&
        unsafe_along(sliding / speed, config.ledge_lookahead)) {
        return true;
    }
    if (!input.jump || move.gravity <= 0.0f) {
        return false;
    }
    const float airtime = 2.0f * move.jump_velocity / move.gravity; // [Units: s]
    if (unsafe_along(input.wish_direction,
                     std::max(config.ledge_lookahead, move.max_speed * airtime))) {
        return true;
    }
    // A jump against a wall stays up long enough for a new goal to steer it aside in the
    // air: no ledge beside it or behind it either.
    const glm::vec3 w = input.wish_direction;
    for (const glm::vec3 aside : {glm::vec3(-w.y, w.x, 0.0f), glm::vec3(w.y, -w.x, 0.0f), -w}) {
        if (unsafe_along(aside, config.ledge_lookahead)) {
            return true;
        }
    }
    return false;
}

} // namespace

std::vector<WanderBot> spawn_wander_bots(const CollisionWorld& world, const MoveConfig& move,
                                         std::span<const maps::SpawnPoint> spawns,
                                         std::size_t count, std::uint64_t seed) {
    std::vector<WanderBot> bots(count);
    for (std::size_t i = 0; i < count; ++i) {
        WanderBot& bot = bots[i];
        bot.random_state = seed * 0x100000001B3ull + i;
        const maps::SpawnPoint& spawn = spawns[(i + seed) % spawns.size()];
        bot.state = spawn_state(world, move, spawn.origin);
        bot.goal = bot.state.position;
        bot.remembered.push_back(bot.state.position);
        bot.since_remember = 0.0f;
    }
    return bots;
}

MoveInput wander_think(WanderBot& bot, const WanderConfig& config, const MoveConfig& move,
                       std::span<const maps::SpawnPoint> spawns, float dt) {
    bot.since_remember += dt;
    if (bot.since_remember >= config.remember_interval && bot.state.on_ground) {
        bot.since_remember = 0.0f;
        if (bot.remembered.size() < config.max_remembered) {
            bot.remembered.push_back(bot.state.position);
        } else {
            bot.remembered[bot.remember_next] = bot.state.position;
            bot.remember_next = (bot.remember_next + 1) % config.max_remembered;
        }
    }
    const float distance = horizontal_distance(bot.state.position, bot.goal);
    if (distance < config.goal_radius) {
        ++bot.goals_reached;
        pick_goal(bot, config, spawns);
    } else {
        bot.since_progress += dt;
        if (distance < bot.best_goal_distance - config.progress_distance) {
            bot.best_goal_distance = distance;
            bot.since_progress = 0.0f;
        } else if (bot.since_progress > config.stuck_seconds) {
            ++bot.goals_abandoned;
            pick_goal(bot, config, spawns);
        }
    }
    MoveInput input;
    glm::vec3 to_goal = bot.goal - bot.state.position;
    to_goal.z = 0.0f;
    const float length = glm::length(to_goal);
    if (length > 1e-3f) {
        input.wish_direction = to_goal / length;
    }
    const float speed = std::hypot(bot.state.velocity.x, bot.state.velocity.y);
    if (speed < config.blocked_speed_fraction * move.max_speed && length > 1e-3f) {
        bot.blocked_time += dt;
    } else {
        bot.blocked_time = 0.0f;
    }
    // Blocked for a moment: jump (and sometimes sidestep) to get over or around it.
    if (bot.blocked_time > 0.25f && bot.state.on_ground) {
        input.jump = true;
        if (random_unit(bot.random_state) < 0.5f) {
            const float side = random_unit(bot.random_state) < 0.5f ? 1.0f : -1.0f;
            input.wish_direction =
                glm::vec3(-input.wish_direction.y * side, input.wish_direction.x * side, 0.0f);
        }
        bot.blocked_time = 0.0f;
    }
    return input;
}

void wander_step(WanderBot& bot, const CollisionWorld& world, const WanderConfig& config,
                 const MoveConfig& move, std::span<const maps::SpawnPoint> spawns,
                 std::span<const maps::Hazard> hazards, float dt) {
    bot.respawned = false;
    if (bot.respawn) {
        if (step_dead(*bot.respawn, bot.state)) {
            bot.respawn.reset();
            bot.respawned = true;
            pick_goal(bot, config, spawns);
        }
        return;
    }
    MoveInput input = wander_think(bot, config, move, spawns, dt);
    if (config.max_safe_drop > 0.0f && bot.state.on_ground &&
        (input.wish_direction.x != 0.0f || input.wish_direction.y != 0.0f) &&
        leads_off_a_ledge(bot, world, config, move, input, hazards)) {
        ++bot.ledges_avoided;
        // Brakes (ground acceleration against its slide, on top of friction) and looks
        // for another goal.
        const glm::vec3 sliding(bot.state.velocity.x, bot.state.velocity.y, 0.0f);
        const float speed = glm::length(sliding);
        input = {};
        if (speed > 1e-3f) {
            input.wish_direction = -sliding / speed;
        }
        pick_goal(bot, config, spawns);
    }
    player_move(world, move, input, dt, bot.state);
    if (!spawns.empty() && touches_hazard(move, bot.state, hazards)) {
        kill_bot(bot, world, config, move, spawns);
    }
}

void kill_bot(WanderBot& bot, const CollisionWorld& world, const WanderConfig& config,
              const MoveConfig& move, std::span<const maps::SpawnPoint> spawns) {
    ++bot.deaths;
    const maps::SpawnPoint& spawn = spawns[next_random(bot.random_state) % spawns.size()];
    if (die(bot.state, spawn_state(world, move, spawn.origin), spawn.yaw_degrees,
            config.respawn_delay_ticks, bot.respawn)) { // no delay
        bot.respawned = true;
        pick_goal(bot, config, spawns);
    }
}

} // namespace dsoc::sim
