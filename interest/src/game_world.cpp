#include "dsoc/interest/game_world.hpp"

#include "dsoc/sim/footing.hpp"

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace dsoc::interest {

namespace {

float wrap_degrees(float deg) {
    float w = std::fmod(deg + 180.0f, 360.0f);
    if (w < 0.0f) {
        w += 360.0f;
    }
    return w - 180.0f;
}

} // namespace

GameWorld::GameWorld(const WorldSettings& settings, std::shared_ptr<const maps::Map> map)
    : map_(std::move(map)), collision_(map_->collision_brushes),
      shot_walls_(map_->collision_brushes, maps::contents_solid) {
    move_.max_speed = settings.max_speed;
    wander_.respawn_delay_ticks = settings.respawn_delay_ticks;
    respawn_delay_ticks_ = settings.respawn_delay_ticks;
    teams_ = settings.teams;
    sounds_ = settings.sounds;
    shots_ = settings.shots;
    seed_ = settings.seed;
    spawns_ = sim::spawn_points_with_footing(collision_, move_, map_->spawn_points,
                                             wander_.max_safe_drop, map_->hazards);
    entities_.reserve(static_cast<std::size_t>(settings.bots) + 64);
    bots_ = sim::spawn_wander_bots(collision_, move_, spawns_,
                                   static_cast<std::size_t>(settings.bots), settings.seed);
    for (std::size_t i = 0; i < bots_.size(); ++i) {
        Entity& bot = insert(Entity{.id = next_id_++, .kind = EntityKind::bot});
        bot.bot = static_cast<std::int32_t>(i);
        bot.move = bots_[i].state;
        bot.team = team_for(bot.id);
    }
    next_spawn_ = static_cast<std::uint32_t>(settings.seed % spawns_.size());
}

Entity& GameWorld::insert(Entity e) {
    if (entities_.empty() || entities_.back().id < e.id) {
        entities_.push_back(std::move(e));
        index_[entities_.back().id] = entities_.size() - 1;
        return entities_.back();
    }
    // A reserved id spawned after a later one: insert in id order.
    const auto at = std::lower_bound(entities_.begin(), entities_.end(), e.id,
                                     [](const Entity& a, std::uint32_t b) { return a.id < b; });
    const auto index = at - entities_.begin();
    entities_.insert(at, std::move(e));
    rebuild_index();
    return entities_[static_cast<std::size_t>(index)];
}

std::uint32_t GameWorld::reserve_player() {
    return reserve_players(1);
}

std::uint32_t GameWorld::reserve_players(std::uint32_t count) {
    if (count > ids_left()) {
        return 0;
    }
    const std::uint32_t first = next_id_;
    next_id_ += count;
    return first;
}

std::uint32_t GameWorld::spawn_player() {
    const std::uint32_t id = reserve_player();
    if (id != 0) {
        spawn_reserved(id);
    }
    return id;
}

Entity GameWorld::new_player(std::uint32_t id) {
    assert(id != 0 && id < next_id_ && find(id) == nullptr); // reserved, not spawned yet
    const auto& spawn = spawns_[next_spawn_++ % spawns_.size()];
    Entity p{.id = id, .kind = EntityKind::player};
    p.move = sim::spawn_state(collision_, move_, spawn.origin);
    p.yaw_deg = wrap_degrees(spawn.yaw_degrees);
    p.team = team_for(id);
    return p;
}

void GameWorld::spawn_reserved(std::uint32_t id) {
    insert(new_player(id));
}

void GameWorld::spawn_reserved(std::span<const std::uint32_t> ids) {
    if (ids.empty()) {
        return;
    }
    std::vector<std::uint32_t> sorted(ids.begin(), ids.end());
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    const std::size_t old_size = entities_.size();
    const bool after_all = old_size == 0 || entities_.back().id < sorted.front();
    for (const std::uint32_t id : sorted) {
        entities_.push_back(new_player(id));
    }
    if (after_all) { // in order already: only the new ones need an index entry
        for (std::size_t i = old_size; i < entities_.size(); ++i) {
            index_[entities_[i].id] = i;
        }
        return;
    }
    std::inplace_merge(entities_.begin(), entities_.begin() + static_cast<std::ptrdiff_t>(old_size),
                       entities_.end(),
                       [](const Entity& a, const Entity& b) { return a.id < b.id; });
    rebuild_index();
}

visibility::TeamId GameWorld::team_for(std::uint32_t id) const {
    return teams_ > 0
               ? static_cast<visibility::TeamId>((id - 1) % static_cast<std::uint32_t>(teams_) + 1)
               : visibility::kNoTeam;
}

void GameWorld::set_team(std::uint32_t id, visibility::TeamId team) {
    const auto it = index_.find(id);
    if (it != index_.end()) {
        entities_[it->second].team = team;
    }
}

void GameWorld::rebuild_index() {
    index_.clear();
    for (std::size_t i = 0; i < entities_.size(); ++i) {
        index_[entities_[i].id] = i;
    }
}

void GameWorld::remove(std::uint32_t id) {
    const auto it = index_.find(id);
    if (it == index_.end()) {
        return;
    }
    entities_.erase(entities_.begin() + static_cast<std::ptrdiff_t>(it->second));
    rebuild_index();
}

void GameWorld::remove(std::span<const std::uint32_t> ids) {
    if (ids.empty()) {
        return;
    }
    std::vector<std::uint32_t> sorted(ids.begin(), ids.end());
    std::sort(sorted.begin(), sorted.end());
    std::erase_if(entities_, [&](const Entity& e) {
        return std::binary_search(sorted.begin(), sorted.end(), e.id);
    });
    rebuild_index();
}

const Entity* GameWorld::find(std::uint32_t id) const {
    const auto it = index_.find(id);
    return it == index_.end() ? nullptr : &entities_[it->second];
}

visibility::Aabb GameWorld::box_of(const Entity& e) const {
    return {e.move.position + move_.mins, e.move.position + move_.maxs};
}

glm::vec3 GameWorld::eye_of(const Entity& e) const {
    return e.move.position + glm::vec3(0.0f, 0.0f, move_.eye_height);
}

std::optional<glm::vec3> GameWorld::arrival_eye_of(const Entity& e) const {
    if (!e.respawn) {
        return std::nullopt;
    }
    return e.respawn->arrival.position + glm::vec3(0.0f, 0.0f, move_.eye_height);
}

void GameWorld::set_player_input(std::uint32_t id, glm::vec3 wish, bool jump, float yaw_deg,
                                 float pitch_deg) {
    const auto it = index_.find(id);
    if (it == index_.end()) {
        return;
    }
    Entity& e = entities_[it->second];
    wish.z = 0.0f;
    const float len = glm::length(wish);
    e.input.wish_direction = len > 1e-6f ? wish / len : glm::vec3(0.0f);
    e.input.jump = jump;
    e.yaw_deg = wrap_degrees(yaw_deg);
    e.pitch_deg = std::clamp(pitch_deg, -90.0f, 90.0f);
}

void GameWorld::fire(std::uint32_t id) {
    if (const auto it = index_.find(id); it != index_.end()) {
        entities_[it->second].firing = true;
    }
}

void GameWorld::mirror(std::vector<Entity> entities, std::uint64_t frags, std::uint32_t next_id) {
    std::uint32_t previous = 0;
    for (const Entity& e : entities) {
        if (e.id <= previous || e.id >= next_id) {
            throw std::invalid_argument("GameWorld::mirror: entity id " + std::to_string(e.id) +
                                        " after " + std::to_string(previous) +
                                        " (ids must increase and stay below the next id " +
                                        std::to_string(next_id) + ")");
        }
        previous = e.id;
    }
    entities_ = std::move(entities);
    for (Entity& e : entities_) {
        e.bot = -1; // a mirror has no brains: its entities move only by the next mirror()
    }
    frags_ = frags;
    next_id_ = next_id;
    mirrored_ = true;
    rebuild_index();
}

void GameWorld::step(float dt, const ParallelFor& parallel) {
    if (mirrored_) {
        throw std::logic_error("GameWorld::step on a mirror: it moves only by mirror()");
    }
    died_.assign(entities_.size(), 0);
    fired_.assign(entities_.size(), 0);
    const std::uint64_t step = steps_++;
    const auto move_one = [this, dt, step](std::size_t i) {
        Entity& e = entities_[i];
        if (e.bot >= 0) {
            e.firing = sim::bot_fires(seed_, e.id, step, sounds_, dt);
            sim::WanderBot& brain = bots_[static_cast<std::size_t>(e.bot)];
            const std::uint32_t deaths = brain.deaths;
            sim::wander_step(brain, collision_, wander_, move_, spawns_, map_->hazards, dt);
            if (brain.deaths != deaths) {
                e.health = sim::kMaxHealth; // a hazard: full again, as it will respawn
            }
            e.move = brain.state;
            e.teleported = brain.respawned;
            e.respawn = brain.respawn;
            const glm::vec3 v = e.move.velocity;
            if (v.x * v.x + v.y * v.y > 1.0f) {
                e.yaw_deg = glm::degrees(std::atan2(v.y, v.x));
            }
        } else if (e.respawn) {
            e.teleported = sim::step_dead(*e.respawn, e.move);
            if (e.teleported) {
                e.yaw_deg = wrap_degrees(e.respawn->yaw_degrees);
                e.respawn.reset();
            }
        } else {
            sim::player_move(collision_, move_, e.input, dt, e.move);
            e.teleported = false;
            // A player who touches a hazard dies (its spawn point is picked below).
            died_[i] = static_cast<std::uint8_t>(!spawns_.empty() &&
                                                 sim::touches_hazard(move_, e.move, map_->hazards));
        }
        const bool alive = !e.respawn && died_[i] == 0;
        sim::step_sounds(e.audible, e.move, alive, e.firing, move_.max_speed, sounds_, dt);
        fired_[i] = static_cast<std::uint8_t>(alive && e.firing);
        e.firing = false;
    };
    if (parallel) {
        parallel(entities_.size(), move_one);
    } else {
        for (std::size_t i = 0; i < entities_.size(); ++i) {
            move_one(i);
        }
    }
    resolve_shots();
    // The dead players get the next spawn points in id order, the bots killed by shots
    // theirs from their own streams; they are put there respawn_delay_ticks steps later
    // (at once without a delay, as bots are).
    for (std::size_t i = 0; i < entities_.size(); ++i) {
        if (died_[i] == 0) {
            continue;
        }
        Entity& e = entities_[i];
        e.health = sim::kMaxHealth; // as it will respawn
        if (e.bot >= 0) {
            sim::WanderBot& brain = bots_[static_cast<std::size_t>(e.bot)];
            sim::kill_bot(brain, collision_, wander_, move_, spawns_);
            e.move = brain.state;
            e.teleported = brain.respawned;
            e.respawn = brain.respawn;
            continue;
        }
        const auto& spawn = spawns_[next_spawn_++ % spawns_.size()];
        // Shot on the step it arrived at a spawn point: it still jumped there this step.
        e.teleported = sim::die(e.move, sim::spawn_state(collision_, move_, spawn.origin),
                                spawn.yaw_degrees, respawn_delay_ticks_, e.respawn) ||
                       e.teleported;
        if (e.teleported) {
            e.yaw_deg = wrap_degrees(spawn.yaw_degrees);
        }
    }
}

void GameWorld::resolve_shots() {
    if (shots_.damage <= 0 || spawns_.empty() ||
        std::find(fired_.begin(), fired_.end(), 1) == fired_.end()) {
        return; // nothing can be hit, or nobody fired: no boxes to gather this step
    }
    const std::size_t count = entities_.size();
    shot_boxes_.resize(count);
    hittable_.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        const Entity& e = entities_[i];
        shot_boxes_[i] = box_of(e);
        hittable_[i] = static_cast<std::uint8_t>(!e.respawn && died_[i] == 0);
    }
    // In id order, each against the world after this step's moves; one killed by an
    // earlier shot of the step fires no more.
    for (std::size_t i = 0; i < count; ++i) {
        if (fired_[i] == 0 || hittable_[i] == 0) {
            continue;
        }
        const Entity& shooter = entities_[i];
        const glm::vec3 direction = sim::view_direction(shooter.yaw_deg, shooter.pitch_deg);
        if (!std::isfinite(direction.x) || !std::isfinite(direction.y) ||
            !std::isfinite(direction.z)) {
            continue; // angles the caller should have refused (set_player_input)
        }
        const auto hit = sim::first_hit(shot_walls_, eye_of(shooter), direction, shots_.range,
                                        shot_boxes_, hittable_, i);
        if (!hit) {
            continue;
        }
        Entity& target = entities_[*hit];
        target.health -= shots_.damage;
        if (target.health <= 0) {
            hittable_[*hit] = 0;
            died_[*hit] = 1;
            ++frags_;
        }
    }
}

} // namespace dsoc::interest
