// dsoc-eval: how much traffic each interest policy saves, what it costs the server,
// and whether it ever hides an entity a player should see, against an Embree ray
// oracle. Deterministic for a seed; no sockets. docs/evaluation.md.

#include "dsoc/cli/program.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/eval/evaluation.hpp"
#include "dsoc/eval/policies.hpp"
#include "dsoc/eval/report.hpp"
#include "dsoc/eval/scenario.hpp"

#include <CLI/CLI.hpp>

#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

int main(int argc, char** argv) {
    using namespace dsoc::eval;
    CLI::App app{"dsoc-eval: deterministic in-process comparison of interest policies "
                 "(traffic, server CPU, pop-in violations, exposure) against an Embree "
                 "ray-cast oracle. Prints a Markdown table on stdout."};
    dsoc::cli::set_up(app, "dsoc-eval");
    std::string scenarios_path = default_scenarios_path();
    std::string scenario_name = "arena-64";
    std::string map;
    std::string policy_list;
    double duration = 0.0;
    std::uint64_t seed = 0;
    bool seed_set = false;
    int viewers = 0;
    int bots = 0;
    int teams = -1;
    std::optional<bool> sounds;
    int oracle_every = 0;
    int oracle_clients = -1;
    EvalOptions options;
    std::string json_path;
    bool list = false;
    bool quiet = false;
    dsoc::cli::add_setting(app, "--scenarios", scenarios_path, "scenarios file");
    dsoc::cli::add_setting(app, "--scenario", scenario_name, "scenario name (see --list)");
    app.add_flag("--list", list, "list the scenarios and exit");
    app.add_option("--map", map, "override the scenario's map (name, path, gen:city, gen:rooms)");
    app.add_option("--policy", policy_list,
                   "comma-separated policies (default: the scenario's list, else all): broadcast, "
                   "distance, occlusion, dsoc, dsoc-tbvs (with TBVs), dsoc-explicit, dsoc-fuzzy, "
                   "raycast; over the map's "
                   "baked table (--bake-cell-size; baked on first use): dsoc-baked, dsoc-table; "
                   "diagnostic: occlusion-k0");
    app.add_option("--duration", duration, "override the simulated time [s]");
    app.add_option("--seed", seed, "override the seed")->each([&](const std::string&) {
        seed_set = true;
    });
    app.add_option("--viewers", viewers, "override the number of viewers");
    app.add_option("--bots", bots, "override the number of bots");
    app.add_option("--teams", teams,
                   "override the number of teams (0 = none; teammates are sent whatever they see "
                   "and left out of pop-in and exposure)");
    app.add_option("--sounds", sounds,
                   "footsteps and shots (true/false): what a viewer only hears is sent coarse, "
                   "judged apart from sight");
    app.add_option("--oracle-every", oracle_every,
                   "the oracle judges every K-th tick (and the one before); 1 = every tick");
    app.add_option("--oracle-clients", oracle_clients,
                   "the oracle judges at most this many clients per judged tick (0 = all)");
    dsoc::cli::add_setting(app, "--oracle-grid", options.sample_grid,
                           "oracle samples per side of each box face turned toward the eye");
    dsoc::cli::add_setting(app, "--threads", options.threads, "worker threads");
    app.add_option("--trace", options.trace_path, "write a replication trace (JSON Lines)");
    dsoc::cli::add_setting(app, "--trace-every", options.trace_every,
                           "record every K-th tick in the trace");
    app.add_option("--trace-policy", options.trace_policy,
                   "policy whose decisions the trace records (default: dsoc, else the first)");
    app.add_option("--dsoc-set", options.dsoc_overrides,
                   "DSOCConfig KEY=VALUE for the dsoc policies (repeatable), e.g. "
                   "region_reuse_margin=8");
    app.add_option("--cheapest-share", options.cheapest_share,
                   "emulate an overloaded server: this share of the culling policies' "
                   "client-ticks gets the cheapest conservative answer (the server's fail-open)")
        ->check(CLI::Range(0.0, 1.0));
    dsoc::cli::add_setting(
        app, "--entity-clusters", options.entity_cluster_size,
        "DSOCConfig::entity_cluster_size for occlusion and dsoc alike (0 = off)");
    app.add_flag("--fusion,!--no-fusion", options.fusion,
                 "occluder fusion across cut planes in the culler's shaft stage (default on)");
    dsoc::cli::add_setting(app, "--portal-depth", options.portal_depth,
                           "levels of portal tests in the culler's shaft stage (0 = off)")
        ->check(CLI::Range(0, 4));
    dsoc::cli::add_setting(
        app, "--bake-cell-size", options.bake_cell_size,
        "cell edge of the baked table the dsoc-baked and dsoc-table policies use")
        ->check(CLI::Range(4.0f, 1024.0f));
    dsoc::cli::add_setting(app, "--bake-max-table-mib", options.bake_max_table_mib,
                           "cells grow (by 1.25x) until the baked table fits this many MiB")
        ->check(CLI::Range(1, 65536));
    app.add_option("--bake-dir", options.bake_dir,
                   "cache of baked tables (default: $DSOC_BAKE_DIR, $XDG_CACHE_HOME/dsoc/bakes "
                   "or ~/.cache/dsoc/bakes)");
    app.add_flag("--region-bound", options.region_bound,
                 "also judge pairs from a lattice of eyes over each client's reachable region "
                 "(what any policy covering that region must send; slow)");
    dsoc::cli::add_setting(app, "--region-lattice", options.region_lattice,
                           "eyes per side of the region bound's lattice (n^3 eyes)")
        ->check(CLI::Range(2, 9));
    app.add_option("--json", json_path, "write every figure as JSON to this file");
    app.add_flag("--quiet", quiet, "no progress line on stderr");
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }

    std::vector<Scenario> scenarios;
    std::string error;
    if (!load_scenarios(scenarios_path, scenarios, error)) {
        std::cerr << "dsoc-eval: " << error << "\n";
        return 2;
    }
    if (list) {
        for (const auto& s : scenarios) {
            std::cout << s.name << ": " << s.description << "\n";
        }
        return 0;
    }
    const Scenario* found = nullptr;
    for (const auto& s : scenarios) {
        if (s.name == scenario_name) {
            found = &s;
        }
    }
    if (found == nullptr) {
        std::cerr << "dsoc-eval: no scenario '" << scenario_name << "' in " << scenarios_path
                  << " (--list shows them)\n";
        return 2;
    }
    options.scenario = *found;
    Scenario& sc = options.scenario;
    if (!map.empty()) {
        sc.map = map;
    }
    if (duration > 0.0) {
        sc.duration_s = duration;
    }
    if (seed_set) {
        sc.seed = seed;
    }
    if (viewers > 0) {
        sc.viewers = viewers;
    }
    if (bots > 0) {
        sc.bots = bots;
    }
    if (teams >= 0) {
        sc.teams = teams;
    }
    if (sounds) {
        sc.sounds = *sounds;
    }
    if (oracle_every > 0) {
        sc.oracle_every = oracle_every;
    }
    if (oracle_clients >= 0) {
        sc.oracle_clients = oracle_clients;
    }
    if (const auto problems = validate(sc); !problems.empty()) {
        std::cerr << "dsoc-eval: " << problems.front() << "\n";
        return 2;
    }
    std::stringstream list_stream(policy_list);
    for (std::string name; std::getline(list_stream, name, ',');) {
        if (name.empty()) {
            continue;
        }
        bool known = false;
        for (const auto& n : all_policy_names()) {
            known = known || n == name;
        }
        for (const auto& n : diagnostic_policy_names()) {
            known = known || n == name;
        }
        for (const auto& n : baked_policy_names()) {
            known = known || n == name;
        }
        if (!known) {
            std::cerr << "dsoc-eval: unknown policy '" << name << "'\n";
            return 2;
        }
        options.policies.push_back(name);
    }

    std::string command = "dsoc-eval";
    for (int i = 1; i < argc; ++i) {
        command += " ";
        command += argv[i];
    }
    EvalResult result;
    try {
        result = run_evaluation(options, quiet ? nullptr : &std::cerr);
    } catch (const EvalInputError& e) {
        std::cerr << "dsoc-eval: "
                  << (e.map_spec.empty()
                          ? std::string(e.what())
                          : dsoc::cli::map_load_failure("--map", e.map_spec, e.what()))
                  << "\n";
        return dsoc::cli::exit_usage;
    } catch (const std::exception& e) {
        std::cerr << "dsoc-eval: " << e.what() << "\n";
        return dsoc::cli::exit_failure;
    }
    write_markdown(result, command, std::cout);
    if (!json_path.empty()) {
        std::ofstream out(json_path);
        out << to_json(result, command);
        if (!out) {
            std::cerr << "dsoc-eval: cannot write " << json_path << "\n";
            return 1;
        }
    }
    return 0;
}
