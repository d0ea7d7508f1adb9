#pragma once
// The command-line flags dsoc-server and dsoc-tick-bench share, bound to ServerConfig
// fields: each setting's flag and help text written once. Header-only, for the
// programs: only they link CLI11 (through dsoc::cli), not dsoc_server_core.

#include "dsoc/cli/choice_option.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/server/server_config.hpp"

namespace dsoc::server {

/// The world: map, tick rate, bots, teams, sounds, seed.
template <class App>
void add_world_options(App& app, ServerConfig& config) {
    cli::add_setting(app, "--map", config.map,
                     "Map: name (e.g. oa_dm4), path to .bsp/text map, or gen:city / gen:rooms");
    cli::add_setting(app, "--tick-rate", config.tick_rate, "Ticks (snapshots) per second [Hz]");
    cli::add_setting(app, "--bots", config.bots, "Wandering bots");
    cli::add_setting(app, "--teams", config.teams,
                     "Teams (0 = none); teammates are sent whatever they see");
    cli::add_setting(app, "--sounds", config.sounds,
                     "Footsteps and shots: what a client hears but cannot see is sent coarse, "
                     "without angles (true/false)");
    cli::add_setting(app, "--footstep-range", config.footstep_range,
                     "How far footsteps are heard [units]");
    cli::add_setting(app, "--shot-range", config.shot_range, "How far shots are heard [units]");
    cli::add_setting(app, "--bot-shots-per-second", config.bot_shots_per_second,
                     "How often a bot fires, on average [1/s]");
    cli::add_setting(app, "--shot-damage", config.shot_damage,
                     "Health a shot takes from the entity it hits, of 100 (0 = harmless); "
                     "the killed respawn at spawn points");
    cli::add_setting(app, "--seed", config.seed, "Seed for bots and spawns");
}

/// The interest policy and its culler's stages.
template <class App>
void add_policy_options(App& app, ServerConfig& config) {
    cli::add_choice_option(app, "--policy", config.policy,
                           "Interest policy: dsoc | occlusion | pvs | distance | broadcast");
    cli::add_setting(app, "--portal-depth", config.portal_depth,
                     "Levels of portal tests in the culler (0 = off; 2 = tightest, ~4x CPU)");
    cli::add_setting(app, "--baked-stage", config.baked_stage,
                     "The map's baked cell visibility table first (true/false; baked and cached "
                     "on first start: dsoc-bake MAP does it ahead)");
    cli::add_setting(app, "--bake-cell-size", config.bake_cell_size,
                     "Cell edge of the baked table");
    app.add_option("--bake-dir", config.bake_dir, "Cache of baked tables");
    cli::add_choice_option(app, "--exact-stages", config.exact_stages,
                           "With the baked stage: true runs the PVS and shaft tests after the "
                           "table (tighter, dearer); false is the table alone; auto: alone unless "
                           "the map needed cells coarser than --bake-cell-size");
}

} // namespace dsoc::server
