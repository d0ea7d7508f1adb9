#pragma once
// Bots that wander: each walks toward a goal (a random spawn point or a random place
// it has already been, so goals are reachable in practice), jumps when blocked, and
// picks a new goal when it arrives or stops making progress. A bot whose box touches a
// hazard (a pit's trigger_hurt, lava) dies and respawns at a spawn point: a teleport,
// flagged in WanderBot::respawned for that tick, outside the motion_bound() contract.
// The spawn point is picked at death and the bot is put there respawn_delay_ticks steps
// later (sim/respawn.hpp: WanderBot::respawn in between). A bot on the ground does not
// walk off a ledge into the void or a hazard (sim/footing.hpp): it stops there and picks
// another goal. Deterministic given the seed. Bots do not collide with each other.

#include "dsoc/maps/map.hpp"
#include "dsoc/sim/collision_world.hpp"
#include "dsoc/sim/player_move.hpp"
#include "dsoc/sim/respawn.hpp"

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace dsoc::sim {

struct WanderConfig {
    /// A goal this close (horizontally) counts as reached. [Units: world units] [Limit: > 0]
    float goal_radius = 48.0f;
    /// Re-pick the goal when the distance to it has not shrunk by progress_distance
    /// in this long. [Units: s] [Limit: > 0]
    float stuck_seconds = 2.0f;
    float progress_distance = 32.0f; ///< [Units: world units] [Limit: > 0]
    /// Jump when moving slower than this share of max_speed while wanting to move. [Limit: 0..1]
    float blocked_speed_fraction = 0.3f;
    /// How often a visited place is remembered as a possible goal. [Units: s] [Limit: > 0]
    float remember_interval = 1.0f;
    /// Most remembered places per bot (oldest replaced). [Limit: >= 1]
    std::uint32_t max_remembered = 32;
    /// Chance a new goal is a spawn point rather than a remembered place. [Limit: 0..1]
    float spawn_goal_chance = 0.5f;
    /// World steps between a death and the respawn (0: at once). Interest management
    /// needs at least the clients' latency allowance in ticks (sim/respawn.hpp).
    /// [Units: ticks] [Limit: >= 0]
    int respawn_delay_ticks = 0;
    /// A drop deeper than this below the place ahead, or one into a hazard, is a ledge
    /// the bot does not walk off (0: it walks off anything). Quake 3's falling damage
    /// starts at about 250 units of drop and stays small. [Units: world units] [Limit: >= 0]
    float max_safe_drop = 512.0f;
    /// How far ahead of its origin a bot looks for such a ledge: more than it slides
    /// to a stop from full speed under ground friction (about 45 units at Quake 3's).
    /// [Units: world units] [Limit: > 0]
    float ledge_lookahead = 64.0f;
};

struct WanderBot {
    MoveState state;
    glm::vec3 goal{0.0f};
    float best_goal_distance = 0.0f;
    float since_progress = 0.0f; ///< [Units: s]
    float since_remember = 0.0f; ///< [Units: s]
    float blocked_time = 0.0f;   ///< [Units: s]
    std::vector<glm::vec3> remembered;
    std::uint32_t remember_next = 0;
    std::uint64_t random_state = 0;
    std::uint32_t goals_reached = 0;
    std::uint32_t goals_abandoned = 0;
    std::uint32_t deaths = 0;
    std::uint32_t ledges_avoided = 0;      ///< ticks it stopped at a ledge and picked another goal
    bool respawned = false;                ///< the last wander_step teleported it to a spawn point
    std::optional<PendingRespawn> respawn; ///< dead, waiting to be put at a spawn point
};

/// Makes `count` bots, bot i at spawn point (i + seed) % spawns.size() with its own
/// random stream. Precondition: !spawns.empty().
[[nodiscard]] std::vector<WanderBot> spawn_wander_bots(const CollisionWorld& world,
                                                       const MoveConfig& move,
                                                       std::span<const maps::SpawnPoint> spawns,
                                                       std::size_t count, std::uint64_t seed);

/// The input a bot gives this tick (updates its goal bookkeeping).
[[nodiscard]] MoveInput wander_think(WanderBot& bot, const WanderConfig& config,
                                     const MoveConfig& move,
                                     std::span<const maps::SpawnPoint> spawns, float dt);

/// A dead bot: step_dead() (and a new goal when it arrives). A live one: wander_think,
/// on the ground a stop and a new goal instead at a ledge it should not walk off,
/// player_move, then death if the box touches a hazard (respawned at once when
/// config.respawn_delay_ticks is 0, else `respawn` is set).
void wander_step(WanderBot& bot, const CollisionWorld& world, const WanderConfig& config,
                 const MoveConfig& move, std::span<const maps::SpawnPoint> spawns,
                 std::span<const maps::Hazard> hazards, float dt);

/// The living bot dies (a hazard, a shot): it is given a spawn point from its own
/// random stream and respawned there at once when config.respawn_delay_ticks is 0
/// (`respawned` set), else `respawn` is set. Precondition: !spawns.empty().
void kill_bot(WanderBot& bot, const CollisionWorld& world, const WanderConfig& config,
              const MoveConfig& move, std::span<const maps::SpawnPoint> spawns);

} // namespace dsoc::sim
