#pragma once
// The evaluation's world: walking viewers and wandering bots moved by the server's
// own movement code (dsoc::sim), deterministic for a seed. Entity ids are dense:
// viewers are 0 .. viewers-1 (client i views from entity i), bots follow.
//
// The simulation runs `lookahead` ticks ahead of the policies, so that the oracle
// can judge tick t against the eyes the viewer really has at t .. t + lookahead.
// Entities respawn `lookahead` ticks after they die, as on the server (the spawn point
// is picked at death: sim/respawn.hpp), so every respawn within a tick's lookahead
// was decided by that tick and the policies are told where it goes.

#include "dsoc/eval/scenario.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/sim/collision_world.hpp"
#include "dsoc/sim/player_move.hpp"
#include "dsoc/sim/sounds.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/relevance.hpp"

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::eval {

struct EntityFrame {
    visibility::Aabb box;     ///< after this tick's movement
    glm::vec3 position{0.0f}; ///< box origin (sim::MoveState::position)
    glm::vec3 velocity{0.0f}; ///< [Units: world units / s]
    float yaw_deg = 0.0f;     ///< facing, from the horizontal velocity
    bool respawned = false;   ///< teleported to a spawn point this tick
    /// Dead, and where its eye will be when its pending respawn puts it at a spawn
    /// point (within the lookahead: sim/respawn.hpp); nothing while it lives.
    std::optional<glm::vec3> arrival_eye;
    visibility::TeamId team = visibility::kNoTeam; ///< Scenario::teams
    /// How far the sound it makes is heard (0: silent; Scenario::sounds).
    /// [Units: world units]
    float sound_range = 0.0f;
};

struct WorldFrame {
    std::uint64_t tick = 0;
    std::vector<EntityFrame> entities; ///< indexed by entity id
};

/// Loads the scenario's map (generated maps honour city_blocks). Throws
/// std::runtime_error with the loader's message on failure.
[[nodiscard]] maps::Map load_scenario_map(const Scenario& scenario);

class WorldSim {
public:
    /// `map` must outlive the simulation. Frames t .. t + lookahead are kept.
    WorldSim(const maps::Map& map, const Scenario& scenario, int lookahead);

    /// Simulates one more tick at the end of the window and drops the oldest frame.
    void advance();
    /// Frame of tick `first_tick() + k`, 0 <= k <= lookahead.
    [[nodiscard]] const WorldFrame& ahead(int k) const {
        return frames_[static_cast<std::size_t>(k)];
    }
    [[nodiscard]] const WorldFrame& current() const { return frames_.front(); }

    [[nodiscard]] std::size_t entity_count() const { return bots_.size(); }
    [[nodiscard]] std::size_t viewer_count() const { return viewers_; }
    [[nodiscard]] const sim::MoveConfig& move() const { return move_; }
    /// The eye of viewer `v` in `frame`: origin + eye_height.
    [[nodiscard]] glm::vec3 eye(const WorldFrame& frame, std::size_t v) const {
        return frame.entities[v].position + glm::vec3(0.0f, 0.0f, move_.eye_height);
    }

private:
    [[nodiscard]] WorldFrame snapshot(std::uint64_t tick, const WorldFrame* previous) const;
    void step();

    const maps::Map* map_;
    sim::CollisionWorld collision_;
    sim::MoveConfig move_;
    sim::WanderConfig wander_;
    /// The map's spawn points a walker has footing at (sim/footing.hpp).
    std::vector<maps::SpawnPoint> spawns_;
    std::vector<sim::WanderBot> bots_; ///< every entity: viewers first
    std::vector<sim::Audible> sounds_; ///< the sounds each entity makes
    sim::SoundSettings sound_settings_;
    std::uint64_t seed_;
    std::uint64_t steps_ = 0;
    std::size_t viewers_;
    int teams_;
    float dt_;
    std::uint64_t next_tick_ = 0;
    std::deque<WorldFrame> frames_;
};

} // namespace dsoc::eval
