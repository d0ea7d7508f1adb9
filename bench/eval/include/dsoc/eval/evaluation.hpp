#pragma once
// One dsoc-eval run: the scenario's world simulated once, every policy deciding on
// the identical frames, the ray oracle judging a sample of ticks for all of them,
// bytes counted by encoding each client's real Snapshot.

#include "dsoc/eval/metrics.hpp"
#include "dsoc/eval/scenario.hpp"
#include "dsoc/visibility/dsoc_config.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"

#include <cstdint>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace dsoc::eval {

struct EvalOptions {
    Scenario scenario;
    /// Policy names (all_policy_names() when empty), in report order.
    std::vector<std::string> policies;
    /// Worker threads for per-client work and the oracle. [Limit: >= 1]
    int threads = 2;
    /// Oracle samples per box face side (grid x grid per face). [Limit: >= 2]
    int sample_grid = 5;
    /// Replication trace file ("" = none), written every trace_every ticks for
    /// trace_policy ("" = "dsoc" when it runs, else the first policy).
    std::string trace_path;
    int trace_every = 1;
    std::string trace_policy;
    /// DSOCConfig settings (KEY=VALUE, visibility::set_field names) applied to the
    /// dsoc policies (not to occlusion), e.g. region_reuse_margin=8.
    std::vector<std::string> dsoc_overrides;
    /// Occluder fusion in the culling policies' shaft stage (RegionCullerConfig::fusion).
    bool fusion = true;
    /// RegionCullerConfig::portal_depth for the culling policies.
    int portal_depth = visibility::ShaftOcclusion::kDefaultPortalDepth;
    /// DSOCConfig::entity_cluster_size for every InterestManager policy. [Units: world units]
    float entity_cluster_size = visibility::DSOCConfig{}.entity_cluster_size;
    /// An overloaded server, emulated: this share of the culling policies' client-ticks
    /// (the same ones in every run) gets UpdateEffort::cheapest, as the server's
    /// fail-open gives clients past its culling budget. [Limit: 0..1]
    double cheapest_share = 0.0;
    /// Also judge every pair from a lattice of eyes over the client's reachable eye region
    /// (the region the culling policies cover): the region bound. Costly.
    bool region_bound = false;
    /// Eyes per side of that lattice (n^3 eyes, corners included). [Limit: 2..9]
    int region_lattice = 3;
    /// The baked table for dsoc-baked and dsoc-table: cell edge (the cache holds one
    /// table per map and settings) and cache directory ("" = maps::default_bake_dir()).
    /// [Units: world units]
    float bake_cell_size = 32.0f;
    std::string bake_dir;
    /// Cells grow until the bake's dense rows fit this (maps::BakeRequest). [Units: MiB]
    std::uint64_t bake_max_table_mib = 128;
    /// Concrete violations kept per policy for the report.
    std::size_t max_examples = 10;
};

struct EvalResult {
    Scenario scenario;
    std::string map_source;
    std::size_t occluders = 0;
    std::size_t oracle_triangles = 0;
    std::size_t entities = 0;
    int lookahead_ticks = 0;
    int ticks = 0;
    int threads = 1;
    int sample_grid = 5;
    std::vector<PolicyMetrics> policies;

    std::uint64_t oracle_ticks = 0;        ///< ticks the oracle judged
    std::uint64_t oracle_client_ticks = 0; ///< client-ticks it judged
    int oracle_client_stride = 1;          ///< it judged every this-many-th client
    /// Ticks where both t and t-1 were judged: the ideal's bytes are exact there.
    std::uint64_t measured_ticks = 0;
    std::uint64_t ideal_bytes = 0;         ///< on measured ticks, all clients
    std::uint64_t ideal_updates = 0;       ///< enters + updates on measured ticks
    std::uint64_t ideal_visible_pairs = 0; ///< visible-within-allowance pairs on judged ticks
    /// Pairs visible from the reachable eye region (lattice), on judged ticks; only with
    /// EvalOptions::region_bound.
    std::uint64_t region_visible_pairs = 0;
    bool region_bound = false;
    int region_lattice = 3; ///< eyes per side of the region bound's lattice

    std::string trace_path;
    std::string trace_policy;
    std::uint64_t trace_ticks = 0;

    double wall_seconds = 0.0;
    double world_seconds = 0.0;
    double oracle_seconds = 0.0;
    std::vector<double> policy_seconds; ///< wall time per policy (decisions + encoding)
};

/// What the evaluation was told to use is wrong (the scenario's settings, a map that
/// does not load, an unknown policy name): the run did not start.
struct EvalInputError : std::runtime_error {
    /// `map` is the map spec when the map is what did not load, else empty.
    EvalInputError(const std::string& what, std::string map = {})
        : std::runtime_error(what), map_spec(std::move(map)) {}
    std::string map_spec;
};

/// Runs the evaluation; `progress` (may be null) gets a status line about once a
/// second. Throws EvalInputError on a bad scenario, map or policy name, and
/// std::runtime_error when the run fails (a bake, the trace file).
[[nodiscard]] EvalResult run_evaluation(const EvalOptions& options, std::ostream* progress);

} // namespace dsoc::eval
