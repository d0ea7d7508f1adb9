#include "dsoc/server/interest_setup.hpp"

#include "dsoc/cli/progress.hpp"
#include "dsoc/interest/bake_request.hpp"
#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/server/dsoc_settings.hpp"
#include "dsoc/server/startup_stop.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <stdexcept>

namespace dsoc::server {

interest::WorldSettings world_settings(const ServerConfig& config) {
    interest::WorldSettings s;
    s.bots = config.bots;
    s.teams = config.teams;
    s.sounds.enabled = config.sounds;
    s.sounds.footstep_range = config.footstep_range;
    s.sounds.shot_range = config.shot_range;
    s.sounds.bot_shots_per_second = config.bot_shots_per_second;
    s.shots.damage = config.shot_damage;
    s.max_speed = config.max_speed;
    s.seed = config.seed;
    // The shortest delay that keeps respawns from popping entities in (sim/respawn.hpp).
    s.respawn_delay_ticks = lookahead_ticks(config);
    return s;
}

interest::PolicySettings policy_settings(const ServerConfig& config) {
    interest::PolicySettings s;
    s.policy = config.policy;
    s.distance_radius = config.distance_radius;
    s.dsoc = dsoc_config(config);
    s.culler = config.culler;
    s.portal_depth = config.portal_depth;
    s.pvs_stage = config.pvs_stage;
    s.baked_stage = config.baked_stage;
    s.bake_cell_size = config.bake_cell_size;
    s.exact_stages = config.exact_stages;
    s.lookahead_ticks = lookahead_ticks(config);
    return s;
}

std::shared_ptr<const visibility::CellVisibilityTable>
baked_table(const ServerConfig& config, const interest::GameWorld& world,
            const visibility::OccluderScene& scene) {
    maps::BakeRequest request = interest::walking_bake_request(world.move_config());
    request.config.cell_size = config.bake_cell_size;
    request.dir = config.bake_dir;
    // Ctrl-C or SIGTERM during the bake: saved where it stands, taken up next start.
    request.stop = [] { return startup_stop_requested(); };
    const std::string& name = world.map().name;
    cli::ProgressLine progress("baking the cell visibility of " + name);
    request.gave_up = [&](const maps::GridOverBudget& over) {
        progress.restart();
        spdlog::info("baked stage: {}: coarser cells instead", maps::describe(over));
    };
    auto baked = maps::load_or_bake(world.map(), scene, request,
                                    [&](double f, double seconds) { progress(f, seconds); });
    if (!baked) {
        throw std::runtime_error("baked stage: " + baked.error().message());
    }
    if (!baked->cache_problem.empty()) {
        spdlog::warn("baked stage: cached table refused: {}", baked->cache_problem);
    }
    if (baked->resumed_fraction > 0.0) {
        spdlog::info("baked stage: went on from a partial bake {:.1f}% done",
                     100.0 * baked->resumed_fraction);
    }
    if (!baked->write_problem.empty()) {
        spdlog::warn("baked stage: table not saved: {}", baked->write_problem);
    }
    spdlog::info("baked stage: {} {} ({} open cells of {:.0f} units, {:.1f} MiB)",
                 baked->from_cache ? "loaded" : "baked and saved", baked->file.string(),
                 baked->table->open_count(), static_cast<double>(baked->table->grid().cell_size),
                 static_cast<double>(baked->table->memory_bytes()) / (1 << 20));
    return baked->table;
}

std::unique_ptr<interest::InterestPolicy> make_policy(const ServerConfig& config,
                                                      const interest::GameWorld& world) {
    const interest::PolicySettings settings = policy_settings(config);
    return interest::make_policy(settings, world, [&](const visibility::OccluderScene& scene) {
        auto table = baked_table(config, world, scene);
        spdlog::info("baked stage: {} (exact_stages = {})",
                     interest::use_exact_stages(settings, *table)
                         ? "the table, then the exact stages"
                         : "the table alone (the exact stages where it does not cover)",
                     interest::name_of(config.exact_stages));
        return table;
    });
}

} // namespace dsoc::server
