// dsoc-snapshot-bytes: runs an evaluation scenario's world (the same deterministic
// motion as dsoc-eval, no oracle) through every named policy and encodes each
// client's snapshots with the server's compact encoder (dsoc::eval::ClientReplication,
// the current protocol version, every entity on the near tier). Reports, per policy
// and wire:
//   update entries, update bytes per client-tick   the update columns (heads, masks
//                           apart, values)
//   update bytes / moving entity   those over the entity updates that carried a new
//                           position (an entity that did not move costs nothing)
//   frame bytes / client-tick   whole frames (header, tick, enters, leaves included)
//   vs full snapshots       frames against sending every replicated entity's full
//                           state every tick (4-byte header + 9-byte tick + 24 each)
//   frames over 1,200 B, largest frame   what a datagram of that size could not hold
// Each policy is measured twice in the same run: "reliable" is the TCP wire (deltas
// against what was last sent); "acked" the unreliable one (protocol::AckedSnapshotEncoder:
// deltas against the newest frame the client acknowledged, positions as residuals
// against a prediction) over a simulated link of --link-delay ticks each way losing
// --loss of the datagrams each way. Both rows divide their update bytes by the same
// count: the entity updates that carried a new position on the reliable wire. Every
// "acked" snapshot the client applies is checked against the server's frame
// (mismatches: 0, else the exit status is 1).
// Deterministic: the same scenario and seed give the same bytes.

#include "dsoc/cli/program.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/eval/acked_replication.hpp"
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
    std::uint64_t over_mtu = 0;            ///< frames larger than kMtuBytes
    std::uint64_t largest = 0;             ///< the largest frame [bytes]
};

/// The datagram payload a UDP snapshot must fit without being split (issue 18's MTU).
constexpr std::uint64_t kMtuBytes = 1200;

void add(Totals& m, const eval::SnapshotCost& cost, std::uint64_t full_snapshot_bytes) {
    ++m.client_ticks;
    m.enters += cost.enters;
    m.updates += cost.updates;
    m.moving_updates += cost.moving_updates;
    m.update_bytes += cost.update_bytes;
    m.frame_bytes += cost.bytes;
    m.full_snapshot_bytes += full_snapshot_bytes;
    m.over_mtu += cost.bytes > kMtuBytes ? 1 : 0;
    m.largest = std::max<std::uint64_t>(m.largest, cost.bytes);
}

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
    eval::LinkModel link;
    CLI::App app{"dsoc-snapshot-bytes: compact snapshot size per policy on an eval scenario"};
    dsoc::cli::set_up(app, "dsoc-snapshot-bytes");
    dsoc::cli::add_setting(app, "--scenario", scenario_name, "Scenario name");
    dsoc::cli::add_setting(app, "--scenarios", scenarios_path, "Scenarios file");
    dsoc::cli::add_setting(app, "--policies", policy_names, "Policies to run");
    dsoc::cli::add_setting(app, "--seconds", seconds,
                           "Simulated time (overrides the scenario's) [s]");
    dsoc::cli::add_setting(app, "--threads", threads,
                           "Threads over clients (results do not depend on it)");
    dsoc::cli::add_setting(app, "--link-delay", link.one_way_ticks,
                           "acked: ticks a datagram takes one way (the round trip is twice this)")
        ->check(CLI::Range(0, static_cast<int>(protocol::kAckedHistory) / 2));
    dsoc::cli::add_setting(app, "--loss", link.loss, "acked: share of datagrams lost, each way")
        ->check(CLI::Range(0.0, 1.0));
    dsoc::cli::add_setting(app, "--seed", link.seed, "acked: seed of the losses");
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
        std::vector<eval::AckedClientReplication> acked;
        std::vector<eval::SnapshotCost> acked_costs;
        Totals acked_totals;
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
        for (std::size_t c = 0; c < viewers; ++c) {
            run.acked.emplace_back(viewers, link, static_cast<std::uint32_t>(c));
        }
        run.acked_costs.resize(viewers);
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
                const auto tick = static_cast<std::uint64_t>(t);
                run.costs[c] = run.replication[c].send(frame, run.sets[c], run.heard[c], tick,
                                                       s.envelope, s.buffer);
                run.acked_costs[c] =
                    run.acked[c].send(frame, run.sets[c], run.heard[c], tick, s.envelope, s.buffer);
            });
            for (std::size_t c = 0; c < viewers; ++c) {
                const std::uint64_t full_snapshot =
                    4 + 9 + eval::kFullStateBytes * run.sets[c].size();
                add(run.totals, run.costs[c], full_snapshot);
                add(run.acked_totals, run.acked_costs[c], full_snapshot);
            }
        }
        world.advance();
        if ((t + 1) % sc.tick_rate == 0) {
            std::fprintf(stderr, "\rtick %d/%d", t + 1, ticks);
        }
    }
    std::fprintf(stderr, "\n");

    std::printf("dsoc-snapshot-bytes: scenario %s (%s), %d viewers, %zu entities, %d ticks "
                "(%.0f s at %d Hz); compact snapshots, near tier (0.125 units, 4096 angle "
                "steps); acked: %d + %d ticks of delay, %.1f%% loss each way\n\n",
                sc.name.c_str(), sc.map.c_str(), sc.viewers, world.entity_count(), ticks,
                sc.duration_s, sc.tick_rate, link.one_way_ticks, link.one_way_ticks,
                100.0 * link.loss);
    std::printf("| policy | wire | update entries/client-tick | update bytes/client-tick | "
                "update bytes/moving entity | vs reliable | frame bytes/client-tick | vs full "
                "snapshots | frames over 1,200 B | largest frame |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n");
    int status = 0;
    for (const Run& run : runs) {
        // One denominator for both wires: the entity updates that carried a new position
        // on the reliable wire, which sends every one (the same sets, the same ticks).
        const auto moving = static_cast<double>(run.totals.moving_updates);
        const double reliable_per_moving =
            ratio(static_cast<double>(run.totals.update_bytes), moving);
        for (const bool acked : {false, true}) {
            const Totals& m = acked ? run.acked_totals : run.totals;
            const auto ct = static_cast<double>(m.client_ticks);
            const double per_moving = ratio(static_cast<double>(m.update_bytes), moving);
            std::printf("| %.*s | %s | %.1f | %.0f | %.2f | %.3f | %.0f | %.3f | %.1f%% | %llu |\n",
                        static_cast<int>(run.policy->name().size()), run.policy->name().data(),
                        acked ? "acked" : "reliable", ratio(m.updates, ct),
                        ratio(static_cast<double>(m.update_bytes), ct), per_moving,
                        ratio(per_moving, reliable_per_moving),
                        ratio(static_cast<double>(m.frame_bytes), ct),
                        ratio(static_cast<double>(m.frame_bytes),
                              static_cast<double>(m.full_snapshot_bytes)),
                        100.0 * ratio(static_cast<double>(m.over_mtu), ct),
                        static_cast<unsigned long long>(m.largest));
        }
        std::uint64_t mismatches = 0;
        std::uint64_t full = 0;
        std::string problem;
        for (const eval::AckedClientReplication& a : run.acked) {
            mismatches += a.mismatches();
            full += a.full_snapshots();
            problem = problem.empty() ? a.first_problem() : problem;
        }
        std::printf("  %.*s acked: %llu snapshots coded against nothing, %llu frames that "
                    "differed from the server's%s%s\n",
                    static_cast<int>(run.policy->name().size()), run.policy->name().data(),
                    static_cast<unsigned long long>(full),
                    static_cast<unsigned long long>(mismatches),
                    problem.empty() ? "" : "; first rejected snapshot: ", problem.c_str());
        status = mismatches == 0 ? status : 1;
    }
    return status;
}
