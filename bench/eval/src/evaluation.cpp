#include "dsoc/eval/evaluation.hpp"

#include "dsoc/eval/parallel.hpp"
#include "dsoc/eval/ray_oracle.hpp"
#include "dsoc/eval/replication.hpp"
#include "dsoc/eval/visibility_truth.hpp"
#include "dsoc/eval/world_sim.hpp"
#include "dsoc/interest/bake_request.hpp"
#include "dsoc/interest/walking_interest.hpp"
#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/trace/trace_writer.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <iterator>
#include <memory>
#include <ostream>
#include <stdexcept>

namespace dsoc::eval {

namespace {

/// Grid steps along each parameter of a 3 x 3 curved patch when the oracle takes it as
/// triangles: within about 0.1 unit of the curved surface for an arc of 64-unit radius
/// (curved_surface.hpp). The renderer's own tessellation is coarser, so near a curved
/// silhouette the game and the oracle may differ by up to its error (a few units).
constexpr int kOraclePatchSteps = 16;

double thread_cpu_us() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The map's baked table from the cache, baked (and cached) when missing.
std::shared_ptr<const visibility::CellVisibilityTable>
baked_table(const maps::Map& map, const visibility::OccluderScene& scene,
            const sim::MoveConfig& move, const EvalOptions& options, std::ostream* progress) {
    maps::BakeRequest request = interest::walking_bake_request(move);
    request.config.cell_size = options.bake_cell_size;
    request.dir = options.bake_dir;
    request.max_table_bytes = options.bake_max_table_mib << 20;
    request.gave_up = [&](const maps::GridOverBudget& over) {
        if (progress != nullptr) {
            *progress << "\n" << maps::describe(over) << "\n";
        }
    };
    auto baked = maps::load_or_bake(map, scene, request, [&](double fraction, double seconds) {
        if (progress != nullptr) {
            *progress << "\rbaking " << map.name << ": " << static_cast<int>(100.0 * fraction)
                      << "% after " << static_cast<int>(seconds) << " s" << std::flush;
        }
    });
    if (!baked) {
        throw std::runtime_error(baked.error().message());
    }
    if (progress != nullptr) {
        if (!baked->cache_problem.empty()) {
            *progress << "\ncached table refused: " << baked->cache_problem;
        }
        *progress << "\n"
                  << (baked->from_cache ? "baked table loaded from " : "baked table written to ")
                  << baked->file.string() << " (" << baked->table->open_count() << " open cells of "
                  << baked->table->grid().cell_size << " units)\n";
    }
    return baked->table;
}

struct PolicyRun {
    std::unique_ptr<EvalPolicy> policy;
    std::vector<ClientReplication> replication;
    std::vector<std::vector<std::uint32_t>> sets;  ///< this tick's interest set per client
    std::vector<std::vector<std::uint32_t>> heard; ///< of each set, the heard-only ids
    /// With sounds: what each client would know without hearing (its set minus heard).
    std::vector<ClientReplication> sight_replication;
    std::vector<std::vector<std::uint32_t>> sight_sets;
    std::vector<std::uint32_t> sight_bytes; ///< this tick's, per client
    std::vector<SnapshotCost> costs;
    std::vector<float> cpu;
    PolicyMetrics metrics;
};

struct WorkerScratch {
    protocol::pb::Envelope envelope;
    std::vector<std::uint8_t> buffer;
};

/// Compares one client's interest set with the oracle's flags. Pairs a rule other than
/// sight decides (teammates: `frame`'s teams) are counted apart, not judged. Entities
/// of the set in `heard` (sent only because heard, coarse) count as not sent for sight.
void judge_client(const VisibilityTruth& truth, const WorldFrame& frame, std::size_t client,
                  const std::vector<std::uint32_t>& set, const std::vector<std::uint32_t>& heard,
                  std::uint64_t tick, std::size_t max_examples, PolicyMetrics& m) {
    const std::size_t entities = frame.entities.size();
    const visibility::TeamId team = frame.entities[client].team;
    std::size_t k = 0;
    std::size_t h = 0;
    for (std::size_t e = 0; e < entities; ++e) {
        if (e == client) {
            continue;
        }
        while (k < set.size() && set[k] < e) {
            ++k;
        }
        while (h < heard.size() && heard[h] < e) {
            ++h;
        }
        const bool only_heard = h < heard.size() && heard[h] == e;
        const bool replicated = k < set.size() && set[k] == e && !only_heard;
        if (visibility::team_relevance(team, frame.entities[e].team) !=
            visibility::Relevance::sight) {
            m.checked_by_rule += 1;
            m.missed_by_rule += replicated ? 0 : 1; // an `always` pair must be sent
            continue;
        }
        const std::uint8_t f = truth.at(client, e);
        if (only_heard) {
            ++m.checked_heard;
            m.heard_visible += (f & VisibilityTruth::kLookahead) != 0 ? 1 : 0;
        }
        if (replicated) {
            ++m.checked_replicated;
            if ((f & VisibilityTruth::kLookahead) == 0) {
                ++m.exposed;
            }
            continue;
        }
        if ((f & VisibilityTruth::kPresent) != 0) {
            ++m.popin_present;
        }
        if ((f & VisibilityTruth::kLookahead) != 0) {
            ++m.popin_lookahead;
            if (m.examples.size() < max_examples) {
                m.examples.push_back({tick, static_cast<std::uint32_t>(client),
                                      static_cast<std::uint32_t>(e),
                                      (f & VisibilityTruth::kPresent) != 0});
            }
        }
    }
}

/// The ideal sends `client`'s teammates too (the team rule), whatever they see: adds
/// them to `set` (increasing ids), which stays increasing.
void add_teammates(const WorldFrame& frame, std::size_t client, std::vector<std::uint32_t>& set) {
    const visibility::TeamId team = frame.entities[client].team;
    if (team == visibility::kNoTeam) {
        return;
    }
    const std::size_t seen = set.size();
    for (std::size_t e = 0; e < frame.entities.size(); ++e) {
        if (e != client && frame.entities[e].team == team &&
            !std::binary_search(set.begin(), set.begin() + static_cast<std::ptrdiff_t>(seen),
                                static_cast<std::uint32_t>(e))) {
            set.push_back(static_cast<std::uint32_t>(e));
        }
    }
    std::inplace_merge(set.begin(), set.begin() + static_cast<std::ptrdiff_t>(seen), set.end());
}

} // namespace

EvalResult run_evaluation(const EvalOptions& options, std::ostream* progress) {
    const auto start = std::chrono::steady_clock::now();
    const Scenario& sc = options.scenario;
    if (const auto problems = validate(sc); !problems.empty()) {
        throw EvalInputError("scenario " + sc.name + ": " + problems.front());
    }
    EvalResult result;
    result.scenario = sc;
    result.threads = std::max(1, options.threads);
    result.sample_grid = std::max(2, options.sample_grid);
    const int lookahead = sc.lookahead_ticks();
    result.lookahead_ticks = lookahead;
    const int total_ticks = sc.total_ticks();
    result.ticks = total_ticks;

    const maps::Map map = [&sc] {
        try {
            return load_scenario_map(sc);
        } catch (const std::runtime_error& e) {
            throw EvalInputError(e.what(), sc.map);
        }
    }();
    result.map_source = map.source;
    result.occluders = map.occluders.size();
    std::vector<glm::vec3> patch_triangles;
    for (const maps::CurvedSurface& patch : map.opaque_patches) {
        maps::tessellate(patch, kOraclePatchSteps, patch_triangles);
    }
    const RayOracle rays(map.occluders, patch_triangles);
    result.oracle_triangles = rays.triangle_count();
    WorldSim world(map, sc, lookahead);
    const std::size_t viewers = world.viewer_count();
    const std::size_t entities = world.entity_count();
    result.entities = entities;

    PolicyEnv env;
    env.map = &map;
    env.scenario = &sc;
    env.world = &world;
    env.rays = &rays;
    env.lookahead_ticks = lookahead;
    env.dsoc_overrides = &options.dsoc_overrides;
    env.fusion = options.fusion;
    env.portal_depth = options.portal_depth;
    env.entity_cluster_size = options.entity_cluster_size;
    env.cheapest_share = options.cheapest_share;

    std::vector<std::string> names = options.policies;
    if (names.empty()) {
        names = sc.policies;
    }
    if (names.empty()) {
        names = all_policy_names();
    }
    std::vector<PolicyRun> runs;
    for (const auto& name : names) {
        const bool culling = name == "occlusion" || name.rfind("dsoc", 0) == 0;
        if (culling && !env.scene) {
            env.scene = visibility::OccluderScene::build(map.occluders);
        }
        if ((name == "dsoc-baked" || name == "dsoc-table") && !env.table) {
            env.table = baked_table(map, *env.scene, world.move(), options, progress);
        }
        PolicyRun run;
        run.policy = make_policy(name, env);
        if (!run.policy) {
            throw EvalInputError("unknown policy '" + name + "'");
        }
        run.replication.assign(viewers, ClientReplication(viewers));
        run.sets.resize(viewers);
        run.heard.resize(viewers);
        if (sc.sounds) {
            run.sight_replication.assign(viewers, ClientReplication(viewers));
            run.sight_sets.resize(viewers);
            run.sight_bytes.resize(viewers);
        }
        run.costs.resize(viewers);
        run.cpu.resize(viewers);
        run.metrics.name = name;
        run.metrics.lookahead_ticks = run.policy->lookahead_ticks();
        run.metrics.cpu_us.reserve(viewers * static_cast<std::size_t>(total_ticks));
        runs.push_back(std::move(run));
    }
    result.policy_seconds.assign(runs.size(), 0.0);

    // The trace.
    std::size_t trace_run = runs.size();
    trace::TraceWriter trace_writer;
    if (!options.trace_path.empty()) {
        const std::string wanted = !options.trace_policy.empty() ? options.trace_policy : "dsoc";
        for (std::size_t i = 0; i < runs.size(); ++i) {
            if (runs[i].metrics.name == wanted) {
                trace_run = i;
            }
        }
        if (trace_run == runs.size()) {
            if (!options.trace_policy.empty()) {
                throw EvalInputError("--trace-policy " + wanted + " is not among the policies run");
            }
            trace_run = 0;
        }
        trace::TraceHeader header;
        header.map = map.name;
        header.tick_rate = sc.tick_rate;
        header.policy = runs[trace_run].metrics.name;
        header.lookahead_ticks = runs[trace_run].metrics.lookahead_ticks;
        for (std::size_t i = 0; i < map.occluders.size(); ++i) {
            trace::TraceOccluder o;
            o.id = static_cast<std::uint32_t>(i);
            o.planes = map.occluders[i].planes();
            header.occluders.push_back(std::move(o));
        }
        for (const maps::CurvedSurface& patch : map.opaque_patches) {
            header.patches.push_back({patch.width, patch.height, patch.points});
        }
        std::string error;
        if (!trace_writer.open(options.trace_path, header, error)) {
            throw std::runtime_error("--trace: " + error);
        }
        result.trace_path = options.trace_path;
        result.trace_policy = header.policy;
    }

    std::vector<WorkerScratch> scratch(static_cast<std::size_t>(result.threads));
    std::vector<ClientReplication> ideal(viewers, ClientReplication(viewers));
    std::vector<std::uint32_t> ideal_set;
    VisibilityTruth truth(rays, result.sample_grid);
    const int every = sc.oracle_every;
    const auto stride = static_cast<std::size_t>(sc.oracle_client_stride());
    // The region bound: eyes over the reachable eye region exactly as the culling
    // policies compute it (interest::WalkingInterest::eye_region()), an n x n x n
    // lattice of them.
    result.region_bound = options.region_bound;
    result.region_lattice = options.region_lattice;
    VisibilityTruth::RegionEyes region_eyes;
    std::shared_ptr<const interest::WalkingInterest> walking;
    if (options.region_bound) {
        visibility::DSOCConfig walking_config;
        walking_config.tick_rate = sc.tick_rate;
        walking = std::make_shared<const interest::WalkingInterest>(
            walking_config, map, world.move(), nullptr, lookahead);
        const int n = options.region_lattice;
        region_eyes = [&world, walking, n](std::size_t c, std::vector<glm::vec3>& eyes) {
            const WorldFrame& now = world.current();
            const glm::vec3 eye = world.eye(now, c);
            const float down = std::max(0.0f, -now.entities[c].velocity.z);
            const visibility::Aabb region = walking->eye_region(eye, down);
            const float step = 1.0f / static_cast<float>(n - 1);
            for (int k = 0; k < n * n * n; ++k) {
                const glm::vec3 f(static_cast<float>(k % n), static_cast<float>((k / n) % n),
                                  static_cast<float>(k / (n * n)));
                eyes.push_back(region.min + region.size() * f * step);
            }
        };
    }
    const std::size_t judged_clients = (viewers + stride - 1) / stride;
    result.oracle_client_stride = static_cast<int>(stride);
    auto last_progress = std::chrono::steady_clock::now();

    for (int t = 0; t < total_ticks; ++t) {
        const WorldFrame& frame = world.current();
        const auto tick = static_cast<std::uint64_t>(t);
        // The oracle judges every `every`-th tick and the tick before it (so the
        // ideal's enter/update split on the measured tick is exact).
        const bool measured = t % every == 0 && t >= 1;
        const bool judged = t % every == 0 || (t + 1) % every == 0;

        for (std::size_t p = 0; p < runs.size(); ++p) {
            PolicyRun& run = runs[p];
            const auto policy_start = std::chrono::steady_clock::now();
            const double serial_start = thread_cpu_us();
            run.policy->begin_tick(frame);
            const double serial_share =
                (thread_cpu_us() - serial_start) / static_cast<double>(viewers);
            parallel_for(viewers, result.threads, [&](std::size_t c, int worker) {
                const double t0 = thread_cpu_us();
                run.policy->select(c, frame, run.sets[c], run.heard[c]);
                run.cpu[c] = static_cast<float>(thread_cpu_us() - t0 + serial_share);
                WorkerScratch& s = scratch[static_cast<std::size_t>(worker)];
                run.costs[c] = run.replication[c].send(frame, run.sets[c], run.heard[c], tick,
                                                       s.envelope, s.buffer);
                if (!run.sight_replication.empty()) {
                    std::vector<std::uint32_t>& sight = run.sight_sets[c];
                    sight.clear();
                    std::set_difference(run.sets[c].begin(), run.sets[c].end(),
                                        run.heard[c].begin(), run.heard[c].end(),
                                        std::back_inserter(sight));
                    run.sight_bytes[c] = run.sight_replication[c]
                                             .send(frame, sight, {}, tick, s.envelope, s.buffer)
                                             .bytes;
                }
            });
            PolicyMetrics& m = run.metrics;
            for (std::size_t c = 0; c < viewers; ++c) {
                const SnapshotCost& cost = run.costs[c];
                ++m.client_ticks;
                m.enters += cost.enters;
                m.updates += cost.updates;
                m.leaves += cost.leaves;
                m.bytes += cost.bytes;
                m.replicated_pairs += run.sets[c].size();
                m.heard_pairs += run.heard[c].size();
                m.heard_entries += cost.heard_entries;
                m.sight_bytes += run.sight_bytes.empty() ? 0 : run.sight_bytes[c];
                m.cpu_us.push_back(run.cpu[c]);
                if (measured && c % stride == 0) {
                    m.measured_bytes += cost.bytes;
                }
            }
            result.policy_seconds[p] += seconds_since(policy_start);
        }

        if (judged) {
            const auto oracle_start = std::chrono::steady_clock::now();
            truth.judge(world, lookahead, result.threads, static_cast<int>(stride), region_eyes);
            ++result.oracle_ticks;
            result.oracle_client_ticks += judged_clients;
            if (measured) {
                ++result.measured_ticks;
            }
            for (auto& run : runs) {
                run.metrics.checked_client_ticks += judged_clients;
                for (std::size_t c = 0; c < viewers; c += stride) {
                    judge_client(truth, world.current(), c, run.sets[c], run.heard[c], tick,
                                 options.max_examples, run.metrics);
                }
                run.metrics.live_tbv_sum += run.policy->live_tbvs();
                ++run.metrics.live_tbv_samples;
            }
            WorkerScratch& s = scratch[0];
            for (std::size_t c = 0; c < viewers; c += stride) {
                truth.ideal_set(c, ideal_set);
                add_teammates(world.current(), c, ideal_set);
                result.ideal_visible_pairs += ideal_set.size();
                for (std::size_t e = 0; options.region_bound && e < entities; ++e) {
                    result.region_visible_pairs +=
                        (truth.at(c, e) & VisibilityTruth::kRegion) != 0 ? 1u : 0u;
                }
                const SnapshotCost cost =
                    ideal[c].send(frame, ideal_set, {}, tick, s.envelope, s.buffer);
                if (measured) {
                    result.ideal_bytes += cost.bytes;
                    result.ideal_updates += cost.enters + cost.updates;
                }
            }
            result.oracle_seconds += seconds_since(oracle_start);
        }

        if (trace_writer.is_open() && t % std::max(1, options.trace_every) == 0) {
            trace::TraceTick line;
            line.t = tick;
            line.entities.reserve(entities);
            for (std::size_t e = 0; e < entities; ++e) {
                line.entities.push_back({static_cast<std::uint32_t>(e), frame.entities[e].box});
            }
            for (std::size_t c = 0; c < viewers; ++c) {
                trace::TraceClient client;
                client.id = static_cast<std::uint32_t>(c);
                client.entity = static_cast<std::uint32_t>(c);
                client.eye = world.eye(frame, c);
                client.arrival = frame.entities[c].arrival_eye;
                add_teammates(frame, c, client.always); // sent for their team
                client.replicated = runs[trace_run].sets[c];
                client.heard = runs[trace_run].heard[c];
                line.clients.push_back(std::move(client));
            }
            if (!trace_writer.write_tick(line)) {
                throw std::runtime_error("--trace: writing tick " + std::to_string(t) + " failed");
            }
        }

        const auto world_start = std::chrono::steady_clock::now();
        world.advance();
        result.world_seconds += seconds_since(world_start);

        if (progress != nullptr &&
            (std::chrono::steady_clock::now() - last_progress > std::chrono::seconds(1) ||
             t + 1 == total_ticks)) {
            last_progress = std::chrono::steady_clock::now();
            const double elapsed = seconds_since(start);
            const double left = elapsed / (t + 1) * (total_ticks - t - 1);
            *progress << "\rdsoc-eval " << sc.name << ": tick " << (t + 1) << "/" << total_ticks
                      << ", " << static_cast<int>(elapsed) << " s elapsed, ~"
                      << static_cast<int>(left) << " s left, oracle " << result.oracle_client_ticks
                      << " client-ticks   " << std::flush;
        }
    }
    if (progress != nullptr) {
        *progress << "\n";
    }
    if (trace_writer.is_open()) {
        result.trace_ticks = trace_writer.ticks_written();
        if (!trace_writer.close()) {
            throw std::runtime_error("--trace: closing failed");
        }
    }
    for (auto& run : runs) {
        run.metrics.tbv = run.policy->tbv_summary();
        result.policies.push_back(std::move(run.metrics));
    }
    result.wall_seconds = seconds_since(start);
    return result;
}

} // namespace dsoc::eval
