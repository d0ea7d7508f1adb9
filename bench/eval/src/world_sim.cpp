#include "dsoc/eval/world_sim.hpp"

#include "dsoc/maps/generators.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/map_spec.hpp"
#include "dsoc/sim/footing.hpp"

#include <cmath>
#include <stdexcept>

namespace dsoc::eval {

maps::Map load_scenario_map(const Scenario& scenario) {
    if (scenario.map == "gen:city" && scenario.city_blocks > 0) {
        maps::CityParams params;
        params.blocks_x = scenario.city_blocks;
        params.blocks_y = scenario.city_blocks;
        params.seed = scenario.seed;
        return maps::build_map(maps::generate_city(params),
                               "generator:city:" + std::to_string(scenario.city_blocks));
    }
    auto loaded = maps::load_map(scenario.map, maps::MapSearch::from_environment());
    if (!loaded) {
        throw std::runtime_error(loaded.error().message());
    }
    return std::move(loaded).value();
}

WorldSim::WorldSim(const maps::Map& map, const Scenario& scenario, int lookahead)
    : map_(&map), collision_(map.collision_brushes), seed_(scenario.seed),
      viewers_(static_cast<std::size_t>(scenario.viewers)), teams_(scenario.teams),
      dt_(1.0f / static_cast<float>(scenario.tick_rate)) {
    wander_.respawn_delay_ticks = lookahead;
    sound_settings_.enabled = scenario.sounds;
    if (map.spawn_points.empty()) {
        throw std::runtime_error("map " + map.name + " has no spawn points");
    }
    const std::size_t count =
        static_cast<std::size_t>(scenario.viewers) + static_cast<std::size_t>(scenario.bots);
    spawns_ = sim::spawn_points_with_footing(collision_, move_, map.spawn_points,
                                             wander_.max_safe_drop, map.hazards);
    bots_ = sim::spawn_wander_bots(collision_, move_, spawns_, count, scenario.seed);
    sounds_.resize(count);
    frames_.push_back(snapshot(next_tick_++, nullptr));
    for (int k = 0; k < lookahead; ++k) {
        step();
        frames_.push_back(snapshot(next_tick_++, &frames_.back()));
    }
}

void WorldSim::step() {
    const std::uint64_t step = steps_++;
    for (std::size_t i = 0; i < bots_.size(); ++i) {
        sim::WanderBot& bot = bots_[i];
        sim::wander_step(bot, collision_, wander_, move_, spawns_, map_->hazards, dt_);
        const bool fired =
            sim::bot_fires(seed_, static_cast<std::uint32_t>(i), step, sound_settings_, dt_);
        sim::step_sounds(sounds_[i], bot.state, !bot.respawn, fired, move_.max_speed,
                         sound_settings_, dt_);
    }
}

void WorldSim::advance() {
    step();
    frames_.push_back(snapshot(next_tick_++, &frames_.back()));
    frames_.pop_front();
}

WorldFrame WorldSim::snapshot(std::uint64_t tick, const WorldFrame* previous) const {
    WorldFrame f;
    f.tick = tick;
    f.entities.resize(bots_.size());
    for (std::size_t i = 0; i < bots_.size(); ++i) {
        const auto& s = bots_[i].state;
        EntityFrame& e = f.entities[i];
        e.position = s.position;
        e.velocity = s.velocity;
        e.box = {s.position + move_.mins, s.position + move_.maxs};
        e.respawned = bots_[i].respawned;
        e.sound_range = sim::audible_range(sounds_[i], sound_settings_);
        if (teams_ > 0) {
            e.team = static_cast<visibility::TeamId>(i % static_cast<std::size_t>(teams_) + 1);
        }
        if (bots_[i].respawn) {
            e.arrival_eye =
                bots_[i].respawn->arrival.position + glm::vec3(0.0f, 0.0f, move_.eye_height);
        }
        const float speed2 = s.velocity.x * s.velocity.x + s.velocity.y * s.velocity.y;
        if (speed2 > 1.0f) {
            e.yaw_deg = std::atan2(s.velocity.y, s.velocity.x) * 57.2957795f;
        } else if (previous != nullptr) {
            e.yaw_deg = previous->entities[i].yaw_deg;
        }
    }
    return f;
}

} // namespace dsoc::eval
