#pragma once
// The command-line flags dsoc-server and dsoc-tick-bench share, bound to ServerConfig
// fields: each setting's flag and help text written once. Header-only, for the
// programs: only they link CLI11 (through dsoc::cli), not dsoc_server_core.

#include "dsoc/cli/choice_option.hpp"
#include "dsoc/server/server_config.hpp"

namespace dsoc::server {

/// The world: map, tick rate, bots, teams, sounds, seed.
template <class App>
void add_world_options(App& app, ServerConfig& config) {
    app.add_option("--map", config.map,
                   "Map: name (e.g. oa_dm4), path to .bsp/text map, or gen:city / gen:rooms")
        ->capture_default_str();
    app.add_option("--tick-rate", config.tick_rate, "Ticks (snapshots) per second [Hz]")
        ->capture_default_str();
    app.add_option("--bots", config.bots, "Wandering bots")->capture_default_str();
    app.add_option("--teams", config.teams,
                   "Teams (0 = none); teammates are sent whatever they see")
        ->capture_default_str();
    app.add_option("--sounds", config.sounds,
                   "Footsteps and shots: what a client hears but cannot see is sent coarse, "
                   "without angles (true/false)")
        ->capture_default_str();
    app.add_option("--footstep-range", config.footstep_range, "How far footsteps are heard [units]")
        ->capture_default_str();
    app.add_option("--shot-range", config.shot_range, "How far shots are heard [units]")
        ->capture_default_str();
    app.add_option("--bot-shots-per-second", config.bot_shots_per_second,
                   "How often a bot fires, on average [1/s]")
        ->capture_default_str();
    app.add_option("--seed", config.seed, "Seed for bots and spawns")->capture_default_str();
}

/// The interest policy and its culler's stages.
template <class App>
void add_policy_options(App& app, ServerConfig& config) {
    cli::add_choice_option(app, "--policy", config.policy,
                           "Interest policy: dsoc | occlusion | pvs | distance | broadcast");
    app.add_option("--portal-depth", config.portal_depth,
                   "Levels of portal tests in the culler (0 = off; 2 = tightest, ~4x CPU)")
        ->capture_default_str();
    app.add_option("--baked-stage", config.baked_stage,
                   "The map's baked cell visibility table first (true/false; baked and cached "
                   "on first start: dsoc-bake MAP does it ahead)")
        ->capture_default_str();
    app.add_option("--bake-cell-size", config.bake_cell_size, "Cell edge of the baked table")
        ->capture_default_str();
    app.add_option("--bake-dir", config.bake_dir, "Cache of baked tables");
    cli::add_choice_option(app, "--exact-stages", config.exact_stages,
                           "With the baked stage: true runs the PVS and shaft tests after the "
                           "table (tighter, dearer); false is the table alone; auto: alone unless "
                           "the map needed cells coarser than --bake-cell-size");
}

} // namespace dsoc::server
