#pragma once
// An authoritative world of entities, bots and players, walking on a map with
// Quake 3 style movement (dsoc::sim): the server's world, and the one dsoc-inspect
// runs in-process. Clients only send intent; the world moves every entity, so every
// entity obeys sim::motion_bound() — the speed contract that interest policies and
// TBVs rely on. A bot or player whose box touches a hazard (a pit, lava) dies and
// respawns at a spawn point (a teleport, flagged for that tick) respawn_delay_ticks
// steps later; the spawn point is picked at death (sim/respawn.hpp), so a client's
// interest can cover where it will be (EntityView::arrival_eye). Entities running
// and firing make sounds (sim/sounds.hpp; EntityView::sound_range), heard by the
// clients within range (interest/hearing.hpp).

#include "dsoc/interest/world_view.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/sim/collision_world.hpp"
#include "dsoc/sim/player_move.hpp"
#include "dsoc/sim/respawn.hpp"
#include "dsoc/sim/shots.hpp"
#include "dsoc/sim/sounds.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/relevance.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace dsoc::interest {

/// What a GameWorld is made of besides its map.
struct WorldSettings {
    /// Wandering bots. [Limit: >= 0]
    int bots = 200;
    /// Horizontal speed bound of every entity. [Units: world units/s] [Limit: > 0]
    float max_speed = 320.0f;
    /// Seed for bots and spawn positions; the same seed gives the same bot motion.
    std::uint64_t seed = 1;
    /// World steps between a death and the respawn. At least the clients' latency
    /// allowance in ticks, or a respawn inside it pops entities in (sim/respawn.hpp).
    /// [Units: ticks] [Limit: >= 0]
    int respawn_delay_ticks = 0;
    /// Teams (0: none): entity `id`, bot or player, plays for team (id - 1) % teams + 1
    /// (GameWorld::team_for), so a player's team is known when its id is reserved.
    /// Teammates are always replicated to each other (relevance.hpp). [Limit: 0..1000]
    int teams = 0;
    /// Footsteps and shots (sim/sounds.hpp): who hears whom (interest/hearing.hpp).
    sim::SoundSettings sounds;
    /// What a shot does to the entity it hits (sim/shots.hpp).
    sim::ShotSettings shots;
};

enum class EntityKind : std::uint8_t { bot = 0, player = 1 };

struct Entity {
    std::uint32_t id = 0;
    EntityKind kind = EntityKind::bot;
    sim::MoveState move;                        ///< position is the origin (feet + 24), world units
    float yaw_deg = 0.0f;                       ///< [-180, 180)
    float pitch_deg = 0.0f;                     ///< [-90, 90]
    sim::MoveInput input;                       ///< players: this tick's intent
    std::int32_t bot = -1;                      ///< index into the bot brains, or -1
    bool teleported = false;                    ///< respawned during the last step()
    std::optional<sim::PendingRespawn> respawn; ///< dead, waiting to be put at a spawn point
    visibility::TeamId team = visibility::kNoTeam;
    bool firing = false;          ///< players: fires in the next step() (GameWorld::fire)
    int health = sim::kMaxHealth; ///< shots take it (sim/shots.hpp); full again at each death
    sim::Audible audible;         ///< the sounds it is making
};

class GameWorld final : public WorldView {
public:
    /// `map` must outlive the world and have at least one spawn point.
    GameWorld(const WorldSettings& settings, std::shared_ptr<const maps::Map> map);

    /// Adds a player entity at a spawn point; returns its id (never 0, never reused), or
    /// 0 (nothing added) when the ids are used up (ids_left()). The same as
    /// spawn_reserved(reserve_player()).
    std::uint32_t spawn_player();
    /// An id for a player entity not in the world yet (never 0, never reused), so that
    /// a client can be told its entity before it is spawned (the server answers hellos
    /// while the world is being read by the tick's jobs), or 0 when the ids are used up.
    /// Does not touch entities(). The same as reserve_players(1).
    [[nodiscard]] std::uint32_t reserve_player();
    /// The first of `count` consecutive ids reserved as reserve_player() reserves one,
    /// or 0 (nothing reserved) when fewer than `count` are left (ids_left()).
    [[nodiscard]] std::uint32_t reserve_players(std::uint32_t count);
    /// Ids reserve_players() can still hand out: ids are 32-bit and never wrap to 0 or
    /// repeat, so every id stays below 2^32 - 1 (next_id() fits in 32 bits). [Limit: ids]
    [[nodiscard]] std::uint32_t ids_left() const { return UINT32_MAX - next_id_; }
    /// Adds the player entity `id` (from reserve_player(), not spawned yet) at the next
    /// spawn point, keeping entities() in increasing id order.
    void spawn_reserved(std::uint32_t id);
    /// Adds the player entities `ids` (each from reserve_player(), not spawned yet; any
    /// order, an id given twice spawned once) in one pass: the same world as
    /// spawn_reserved(id) for each in increasing id order (the spawn points are dealt in
    /// that order). O(entities + ids log ids), where one by one costs O(entities) each.
    void spawn_reserved(std::span<const std::uint32_t> ids);
    /// The team entity `id` plays for when it joins (WorldSettings::teams; kNoTeam
    /// without teams).
    [[nodiscard]] visibility::TeamId team_for(std::uint32_t id) const;
    /// Moves an entity to `team` (visibility::kNoTeam: none); unknown ids are ignored.
    void set_team(std::uint32_t id, visibility::TeamId team);
    /// Removes an entity; unknown ids are ignored.
    void remove(std::uint32_t id);
    /// Removes the entities `ids` (unknown ones, and repeats, ignored) in one pass: the
    /// same world as remove(id) for each. O(entities log ids).
    void remove(std::span<const std::uint32_t> ids);
    /// Sets a player's intent: `wish` horizontal, clamped to length <= 1; angles are
    /// wrapped and clamped. Non-finite values must be rejected by the caller.
    void set_player_input(std::uint32_t id, glm::vec3 wish, bool jump, float yaw_deg,
                          float pitch_deg);
    /// The player fires in the next step(): a shot heard for the settings' shot_seconds
    /// (sim::SoundSettings). Unknown ids are ignored.
    void fire(std::uint32_t id);

    /// Runs `body(i)` for every i in [0, count), possibly on several threads at once,
    /// and returns when all have returned.
    using ParallelFor =
        std::function<void(std::size_t count, const std::function<void(std::size_t)>& body)>;

    /// Advances every entity by `dt` seconds. Each entity moves on its own (bots with
    /// their own random streams), so the moves may run through `parallel`; then the
    /// step's shots hit in id order (sim/shots.hpp), and the entities that touched a
    /// hazard or lost their health are put at spawn points in id order, so the world is
    /// the same with or without it.
    void step(float dt, const ParallelFor& parallel = {});

    /// All entities in increasing id order.
    [[nodiscard]] const std::vector<Entity>& entities() const { return entities_; }
    /// WorldView: entities()[index] with its box_of() and velocity.
    [[nodiscard]] std::size_t entity_count() const override { return entities_.size(); }
    [[nodiscard]] EntityView entity(std::size_t index) const override {
        const Entity& e = entities_[index];
        return {e.id,
                box_of(e),
                e.move.velocity,
                arrival_eye_of(e),
                e.team,
                sim::audible_range(e.audible, sounds_)};
    }
    [[nodiscard]] const Entity* find(std::uint32_t id) const;
    /// The entity's collision box in world space.
    [[nodiscard]] visibility::Aabb box_of(const Entity& e) const;
    /// Where an entity's view is taken from.
    [[nodiscard]] glm::vec3 eye_of(const Entity& e) const;
    /// Where its view will be taken from once a pending respawn puts it at its spawn
    /// point (within respawn_delay_ticks steps); nothing while it lives.
    [[nodiscard]] std::optional<glm::vec3> arrival_eye_of(const Entity& e) const;
    [[nodiscard]] float max_speed() const { return move_.max_speed; }
    [[nodiscard]] const sim::MoveConfig& move_config() const { return move_; }
    [[nodiscard]] const sim::SoundSettings& sound_settings() const { return sounds_; }
    /// Entities killed by shots since the world began.
    [[nodiscard]] std::uint64_t frags() const { return frags_; }
    /// The id reserve_player() hands out next (every id below it was handed out).
    [[nodiscard]] std::uint32_t next_id() const { return next_id_; }

    /// Makes this world read as another world of the same map and settings does: its
    /// entities (in increasing id order, ids in [1, next_id)), frags and next id
    /// (scale-out: a gateway mirrors the world process's ticks). Entities keep no bot
    /// brain, so a mirror is read, not stepped: step() after mirror() throws
    /// std::logic_error. Throws std::invalid_argument, changing nothing, for ids out of
    /// order or range (a decoder of outside bytes checks them before).
    void mirror(std::vector<Entity> entities, std::uint64_t frags, std::uint32_t next_id);
    [[nodiscard]] bool mirrored() const { return mirrored_; }
    [[nodiscard]] const maps::Map& map() const { return *map_; }
    [[nodiscard]] const std::shared_ptr<const maps::Map>& map_ptr() const { return map_; }

private:
    /// Inserts `e` (its id not in the world) in id order.
    Entity& insert(Entity e);
    /// Player `id` (reserved, not spawned) at the next spawn point, not inserted yet.
    [[nodiscard]] Entity new_player(std::uint32_t id);
    void rebuild_index();
    /// step(): the shots of the entities in fired_, marking the killed in died_.
    void resolve_shots();

    std::shared_ptr<const maps::Map> map_;
    sim::CollisionWorld collision_;
    sim::CollisionWorld shot_walls_; ///< solid brushes only: a player clip stops no shot
    sim::MoveConfig move_;
    sim::WanderConfig wander_;
    /// The map's spawn points a walker has footing at (sim/footing.hpp).
    std::vector<maps::SpawnPoint> spawns_;
    std::vector<Entity> entities_;
    std::vector<sim::WanderBot> bots_;
    std::unordered_map<std::uint32_t, std::size_t> index_;
    std::uint32_t next_id_ = 1;
    std::uint32_t next_spawn_ = 0;
    int respawn_delay_ticks_ = 0;
    int teams_ = 0;
    sim::SoundSettings sounds_;
    sim::ShotSettings shots_;
    std::uint64_t seed_ = 0;
    std::uint64_t steps_ = 0; ///< step() calls so far: the bots' shot draws
    std::uint64_t frags_ = 0;
    bool mirrored_ = false; ///< mirror() was called: no bot brains, never stepped
    /// step(), by index: players who touched a hazard and entities a shot killed; who
    /// fired while alive; the boxes shots may hit and which of them live.
    std::vector<std::uint8_t> died_;
    std::vector<std::uint8_t> fired_;
    std::vector<visibility::Aabb> shot_boxes_;
    std::vector<std::uint8_t> hittable_;
};

} // namespace dsoc::interest
