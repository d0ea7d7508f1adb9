// dsoc-snapshot-bytes: runs an evaluation scenario's world (the same deterministic
// motion as dsoc-eval, no oracle) through every named policy and encodes each
// client's snapshots with the server's compact encoder (dsoc::eval::ClientReplication,
// protocol version 3, every entity on the near tier). Reports, per policy:
//   update bytes / update   the update columns (ids, field masks, deltas) per entity
//                           update; an entity that did not move costs nothing
//   vs full state           that against kFullStateBytes (24: id + five floats)
//   frame bytes / update    whole frames (header, tick, enters, leaves included) per
//                           entity update (enters + updates)
//   vs full snapshots       frames against sending every replicated entity's full
//                           state every tick (4-byte header + 9-byte tick + 24 each)
// Deterministic: the same scenario and seed give the same bytes.

#include "dsoc/cli/program.hpp"
#include "dsoc/eval/parallel.hpp"
#include "dsoc/eval/policies.hpp"
#include "dsoc/eval/replication.hpp"
#include "dsoc/eval/scenario.hpp"
#include "dsoc/eval/world_sim.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace dsoc;

struct Totals {
    std::uint64_t client_ticks = 0;
    std::uint64_t enters = 0;
    std::uint64_t updates = 0;
    std::uint64_t moving_updates = 0;
    std::uint64_t update_bytes = 0;
    std::uint64_t frame_bytes = 0;
    std::uint64_t full_snapshot_bytes = 0; ///< every replicated entity, full state, every tick
};

double ratio(double a, double b) {
    return b > 0.0 ? a / b : 0.0;
}

} // namespace

int main(int argc, char** argv) {
    std::string scenario_name = "arena-64";
    std::string scenarios_path = eval::default_scenarios_path();
    std::vector<std::string> policy_names = {"broadcast", "distance", "pvs", "occlusion", "dsoc"};
    double seconds = 20.0;
    int threads = 2;
    CLI::App app{"dsoc-snapshot-bytes: compact snapshot size per policy on an eval scenario"};
    dsoc::cli::set_up(app, "dsoc-snapshot-bytes");
    app.add_option("--scenario", scenario_name, "Scenario name")->capture_default_str();
    app.add_option("--scenarios", scenarios_path, "Scenarios file")->capture_default_str();
    app.add_option("--policies", policy_names, "Policies to run")->capture_default_str();
    app.add_option("--seconds", seconds, "Simulated time (overrides the scenario's) [s]")
        ->capture_default_str();
    app.add_option("--threads", threads, "Threads over clients (results do not depend on it)")
        ->capture_default_str();
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }

    std::vector<eval::Scenario> scenarios;
    std::string error;
    if (!eval::load_scenarios(scenarios_path, scenarios, error)) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return 2;
    }
    eval::Scenario sc;
    bool found = false;
    for (const auto& s : scenarios) {
        if (s.name == scenario_name) {
            sc = s;
            found = true;
        }
    }
    if (!found) {
        std::fprintf(stderr, "no scenario '%s' in %s\n", scenario_name.c_str(),
                     scenarios_path.c_str());
        return 2;
    }
    if (seconds > 0.0) {
        sc.duration_s = seconds;
    }
    if (const auto problems = eval::validate(sc); !problems.empty()) {
        std::fprintf(stderr, "scenario %s: %s\n", sc.name.c_str(), problems.front().c_str());
        return 2;
    }

    // The scenario's map is an input the run was told to use: one that does not load
    // (or has no spawn points) is a usage error, named with the scenario.
    std::optional<maps::Map> loaded;
    try {
        loaded.emplace(eval::load_scenario_map(sc));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "dsoc-snapshot-bytes: scenario %s: %s\n", sc.name.c_str(),
                     cli::map_load_failure("a scenario's \"map\"", sc.map, e.what()).c_str());
        return cli::exit_usage;
    }
    const maps::Map& map = *loaded;
    const int lookahead = sc.lookahead_ticks();
    std::optional<eval::WorldSim> simulated;
    try {
        simulated.emplace(map, sc, lookahead);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "dsoc-snapshot-bytes: scenario %s: %s\n", sc.name.c_str(), e.what());
        return cli::exit_usage;
    }
    eval::WorldSim& world = *simulated;
    const std::size_t viewers = world.viewer_count();
    eval::PolicyEnv env;
    env.map = &map;
    env.scenario = &sc;
    env.world = &world;
    env.lookahead_ticks = lookahead;
    env.scene = visibility::OccluderScene::build(map.occluders);

    struct Run {
        std::unique_ptr<eval::EvalPolicy> policy;
        std::vector<eval::ClientReplication> replication;
        std::vector<std::vector<std::uint32_t>> sets;
        std::vector<std::vector<std::uint32_t>> heard; ///< of each set, the heard-only ids
        std::vector<eval::SnapshotCost> costs;
        Totals totals;
    };
    std::vector<Run> runs;
    for (const auto& name : policy_names) {
        if (name == "raycast") {
            std::fprintf(stderr, "raycast needs the ray oracle; not supported here\n");
            return 2;
        }
        Run run;
        run.policy = eval::make_policy(name, env);
        if (!run.policy) {
            std::fprintf(stderr, "unknown policy '%s'\n", name.c_str());
            return 2;
        }
        run.replication.assign(viewers, eval::ClientReplication(viewers));
        run.sets.resize(viewers);
        run.heard.resize(viewers);
        run.costs.resize(viewers);
        runs.push_back(std::move(run));
    }

    struct Scratch {
        protocol::pb::Envelope envelope;
        std::vector<std::uint8_t> buffer;
    };
    std::vector<Scratch> scratch(static_cast<std::size_t>(std::max(1, threads)));
    const int ticks = sc.total_ticks();
    for (int t = 0; t < ticks; ++t) {
        const eval::WorldFrame& frame = world.current();
        for (Run& run : runs) {
            run.policy->begin_tick(frame);
            eval::parallel_for(viewers, threads, [&](std::size_t c, int worker) {
                run.policy->select(c, frame, run.sets[c], run.heard[c]);
                Scratch& s = scratch[static_cast<std::size_t>(worker)];
                run.costs[c] =
                    run.replication[c].send(frame, run.sets[c], run.heard[c],
                                            static_cast<std::uint64_t>(t), s.envelope, s.buffer);
            });
            for (std::size_t c = 0; c < viewers; ++c) {
                const eval::SnapshotCost& cost = run.costs[c];
                Totals& m = run.totals;
                ++m.client_ticks;
                m.enters += cost.enters;
                m.updates += cost.updates;
                m.moving_updates += cost.moving_updates;
                m.update_bytes += cost.update_bytes;
                m.frame_bytes += cost.bytes;
                m.full_snapshot_bytes += 4 + 9 + eval::kFullStateBytes * run.sets[c].size();
            }
        }
        world.advance();
        if ((t + 1) % sc.tick_rate == 0) {
            std::fprintf(stderr, "\rtick %d/%d", t + 1, ticks);
        }
    }
    std::fprintf(stderr, "\n");

    std::printf("dsoc-snapshot-bytes: scenario %s (%s), %d viewers, %zu entities, %d ticks "
                "(%.0f s at %d Hz); compact snapshots, protocol v3, near tier (0.125 units, "
                "4096 angle steps)\n\n",
                sc.name.c_str(), sc.map.c_str(), sc.viewers, world.entity_count(), ticks,
                sc.duration_s, sc.tick_rate);
    std::printf("| policy | updates/client-tick | moving share | update bytes/update | vs full "
                "state (24 B) | frame bytes/update | frame bytes/client-tick | vs full "
                "snapshots |\n|---|---|---|---|---|---|---|---|\n");
    for (const Run& run : runs) {
        const Totals& m = run.totals;
        const auto ct = static_cast<double>(m.client_ticks);
        const double per_update = ratio(static_cast<double>(m.update_bytes), m.updates);
        std::printf(
            "| %.*s | %.1f | %.1f%% | %.2f | %.3f | %.2f | %.0f | %.3f |\n",
            static_cast<int>(run.policy->name().size()), run.policy->name().data(),
            ratio(m.updates, ct), 100.0 * ratio(m.moving_updates, m.updates), per_update,
            per_update / eval::kFullStateBytes,
            ratio(static_cast<double>(m.frame_bytes), m.updates + m.enters),
            ratio(static_cast<double>(m.frame_bytes), ct),
            ratio(static_cast<double>(m.frame_bytes), static_cast<double>(m.full_snapshot_bytes)));
    }
    return 0;
}
