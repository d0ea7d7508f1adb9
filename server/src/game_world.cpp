#include "dsoc/server/game_world.hpp"

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <cmath>

namespace dsoc::server {

namespace {

float wrap_degrees(float deg) {
    float w = std::fmod(deg + 180.0f, 360.0f);
    if (w < 0.0f) {
        w += 360.0f;
    }
    return w - 180.0f;
}

} // namespace

GameWorld::GameWorld(const ServerConfig& config)
    : max_speed_(config.max_speed), bot_speed_(config.max_speed * config.bot_speed_fraction),
      half_size_(config.world_half_size), rng_(config.seed) {
    entities_.reserve(static_cast<std::size_t>(config.bots) + 64);
    for (int i = 0; i < config.bots; ++i) {
        Entity& bot = add(EntityKind::bot);
        bot.position = random_open_point();
        bot.goal = random_open_point();
    }
}

glm::vec3 GameWorld::random_open_point() {
    std::uniform_real_distribution<float> coord(-half_size_ * 0.95f, half_size_ * 0.95f);
    const float x = coord(rng_);
    const float y = coord(rng_);
    return {x, y, 24.0f};
}

Entity& GameWorld::add(EntityKind kind) {
    Entity e;
    e.id = next_id_++;
    e.kind = kind;
    entities_.push_back(e);
    index_[e.id] = entities_.size() - 1;
    return entities_.back();
}

std::uint32_t GameWorld::spawn_player() {
    Entity& p = add(EntityKind::player);
    p.position = random_open_point();
    return p.id;
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

const Entity* GameWorld::find(std::uint32_t id) const {
    const auto it = index_.find(id);
    return it == index_.end() ? nullptr : &entities_[it->second];
}

void GameWorld::set_player_input(std::uint32_t id, glm::vec3 wish, float yaw_deg,
                                 float pitch_deg) {
    const auto it = index_.find(id);
    if (it == index_.end()) {
        return;
    }
    Entity& e = entities_[it->second];
    wish.z = 0.0f; // the skeleton world is flat
    const float len = glm::length(wish);
    e.wish = len > 1.0f ? wish / len : wish;
    e.yaw_deg = wrap_degrees(yaw_deg);
    e.pitch_deg = std::clamp(pitch_deg, -90.0f, 90.0f);
}

void GameWorld::step(float dt) {
    const float limit = half_size_ - 16.0f;
    for (Entity& e : entities_) {
        glm::vec3 velocity{0.0f};
        if (e.kind == EntityKind::bot) {
            glm::vec3 to_goal = e.goal - e.position;
            to_goal.z = 0.0f;
            const float dist = glm::length(to_goal);
            if (dist < bot_speed_ * dt + 1.0f) {
                e.goal = random_open_point();
            } else {
                velocity = to_goal / dist * bot_speed_;
                e.yaw_deg = glm::degrees(std::atan2(to_goal.y, to_goal.x));
            }
        } else {
            velocity = e.wish * max_speed_;
        }
        const float speed = glm::length(velocity);
        if (speed > max_speed_) {
            velocity *= max_speed_ / speed;
        }
        e.velocity = velocity;
        e.position += velocity * dt;
        e.position.x = std::clamp(e.position.x, -limit, limit);
        e.position.y = std::clamp(e.position.y, -limit, limit);
    }
}

} // namespace dsoc::server
