#pragma once
// The server's authoritative entities: bots and players, and how they move.
// Clients only send intent; every entity moves at most `max_speed` units/s, which
// is the speed bound interest policies (and TBVs) rely on.

#include "dsoc/server/server_config.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <random>
#include <unordered_map>
#include <vector>

namespace dsoc::server {

enum class EntityKind : std::uint8_t { bot = 0, player = 1 };

struct Entity {
    std::uint32_t id = 0;
    EntityKind kind = EntityKind::bot;
    glm::vec3 position{0.0f};         ///< origin, world units
    glm::vec3 velocity{0.0f};         ///< units/s
    glm::vec3 half_extents{15.0f, 15.0f, 28.0f};
    float yaw_deg = 0.0f;             ///< [-180, 180)
    float pitch_deg = 0.0f;           ///< [-90, 90]
    glm::vec3 wish{0.0f};             ///< players: movement intent, |wish| <= 1
    glm::vec3 goal{0.0f};             ///< bots: where they wander to
};

class GameWorld {
public:
    explicit GameWorld(const ServerConfig& config);

    /// Adds a player entity at a random open position; returns its id (never 0,
    /// never reused).
    std::uint32_t spawn_player();
    /// Removes an entity; unknown ids are ignored.
    void remove(std::uint32_t id);
    /// Sets a player's intent; `wish` is clamped to length <= 1, angles are wrapped
    /// and clamped. Non-finite values must be rejected by the caller.
    void set_player_input(std::uint32_t id, glm::vec3 wish, float yaw_deg, float pitch_deg);

    /// Advances every entity by `dt` seconds.
    void step(float dt);

    /// All entities in increasing id order.
    [[nodiscard]] const std::vector<Entity>& entities() const { return entities_; }
    [[nodiscard]] const Entity* find(std::uint32_t id) const;
    /// Where an entity's view is taken from.
    [[nodiscard]] static glm::vec3 eye_of(const Entity& e) { return e.position + glm::vec3(0, 0, 26); }
    [[nodiscard]] float max_speed() const { return max_speed_; }

private:
    Entity& add(EntityKind kind);
    glm::vec3 random_open_point();
    void rebuild_index();

    std::vector<Entity> entities_;
    std::unordered_map<std::uint32_t, std::size_t> index_;
    std::uint32_t next_id_ = 1;
    float max_speed_;
    float bot_speed_;
    float half_size_;
    std::mt19937_64 rng_;
};

} // namespace dsoc::server
