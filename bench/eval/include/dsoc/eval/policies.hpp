#pragma once
// The interest policies dsoc-eval compares, all fed the identical world frames; each
// is an interest::InterestPolicy, the server's own where the server has it (broadcast,
// distance, pvs, and the culling policies: interest::CullingPolicy with the eval's
// TBV strategies and culler stages):
//   broadcast      every entity
//   distance       entities whose box comes within a radius of the eye (ring culling)
//   occlusion      the from-region z-pyramid rebuilt every tick, every box tested
//                  every tick (InterestManager with no TBVs and no buffer reuse)
//   dsoc           InterestManager with its defaults (no TBVs: they do not pay)
//   dsoc-tbvs      the same with TBVs, adaptive (the default strategy)
//   dsoc-explicit  the same with fixed-duration TBVs
//   dsoc-fuzzy     the same with predicted (NOT conservative) TBVs
//   raycast        per-pair Embree rays from the eye and from the eye extrapolated by
//                  its velocity x latency (SMAC-style) to the target box's 8 corners
//                  and centre; not conservative (docs/evaluation.md)
//   occlusion-k0   diagnostic, only when named: occlusion from the present eye alone

#include "dsoc/eval/ray_oracle.hpp"
#include "dsoc/eval/scenario.hpp"
#include "dsoc/eval/world_sim.hpp"
#include "dsoc/interest/hearing.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/dsoc_config.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::interest {
class CullingPolicy;
}

namespace dsoc::eval {

struct PolicyEnv {
    const maps::Map* map = nullptr;
    const Scenario* scenario = nullptr;
    const WorldSim* world = nullptr;
    std::shared_ptr<const visibility::OccluderScene> scene;
    const RayOracle* rays = nullptr;
    /// DSOCConfig settings (KEY=VALUE) for the dsoc policies, over their defaults.
    const std::vector<std::string>* dsoc_overrides = nullptr;
    /// RegionCullerConfig::fusion for the culling policies.
    bool fusion = true;
    /// RegionCullerConfig::portal_depth for the culling policies.
    int portal_depth = visibility::ShaftOcclusion::kDefaultPortalDepth;
    /// DSOCConfig::entity_cluster_size for the culling policies. [Units: world units]
    float entity_cluster_size = visibility::DSOCConfig{}.entity_cluster_size;
    /// EvalOptions::cheapest_share. [Limit: 0..1]
    double cheapest_share = 0.0;
    /// The latency allowance the culling policies promise. [Units: ticks]
    int lookahead_ticks = 5;
    /// The map's baked cell visibility table, for the dsoc-baked and dsoc-table
    /// policies (null: those policies are refused).
    std::shared_ptr<const visibility::CellVisibilityTable> table;
};

/// Counters of the InterestManager-based policies, summed over clients.
struct TbvSummary {
    bool available = false;
    std::uint64_t buffer_builds = 0;
    std::uint64_t box_tests = 0;
    std::uint64_t tbv_tests = 0;
    std::uint64_t cluster_tests = 0; ///< entity clusters tested (summed over clients)
    std::uint64_t cluster_hits = 0;  ///< of those, proven hidden
    std::uint64_t tbvs_created = 0;
    std::uint64_t tbvs_merged = 0;
    std::uint64_t tbvs_rejected = 0;
    std::uint64_t tbv_hits = 0;
    std::uint64_t tbvs_expired = 0;
    std::uint64_t evictions = 0;
    std::uint64_t teleports = 0;
    std::uint64_t cheapest_updates = 0; ///< client-ticks at UpdateEffort::cheapest
    std::uint64_t fuzzy_escapes = 0;    ///< entities caught outside their fuzzy TBV
};

/// A policy as dsoc-eval runs it: an interest::InterestPolicy (the server's own, or
/// the evaluation's raycast) over the evaluation's frames, client i viewing from
/// entity i, its own entity left out of its set.
///
/// Threading: begin_tick() is serial; select() may then run concurrently for
/// distinct clients.
class EvalPolicy {
public:
    /// `policy` over `world`'s frames (`world` must outlive it). `lookahead_ticks`: the
    /// ticks of the viewer's own movement it promises to cover (trace header; 0 for the
    /// policies without a latency allowance). `cheapest_share`: the share of client-ticks,
    /// chosen by a hash, answered by select_cheapest() (an emulated overload). [Limit: 0..1]
    EvalPolicy(std::unique_ptr<interest::InterestPolicy> policy, const WorldSim& world,
               int lookahead_ticks, double cheapest_share = 0.0);

    [[nodiscard]] std::string_view name() const { return policy_->name(); }
    [[nodiscard]] int lookahead_ticks() const { return lookahead_ticks_; }
    /// Serial part of a tick: the world is now `frame`. The first call adds every viewer.
    void begin_tick(const WorldFrame& frame);
    /// Client `client`'s interest set in `out` (cleared first): increasing entity ids,
    /// its own entity left out; with them, in `heard` (cleared first), those of them sent
    /// only because the client hears them (interest::Hearing; the heard tier).
    void select(std::size_t client, const WorldFrame& frame, std::vector<std::uint32_t>& out,
                std::vector<std::uint32_t>& heard);
    /// The InterestManager's counters for the culling policies (available = false for
    /// the others).
    [[nodiscard]] TbvSummary tbv_summary() const;
    /// Live TBV groups summed over clients (0 for policies without TBVs).
    [[nodiscard]] std::uint64_t live_tbvs() const { return policy_->tbvs_alive(); }

private:
    /// Whether this client-tick is one of the emulated overload's (cheapest_share_ of
    /// them, chosen by a hash: the same in every run and at any thread count).
    [[nodiscard]] bool over_budget(std::size_t client, std::uint64_t tick) const;

    std::unique_ptr<interest::InterestPolicy> policy_;
    const interest::CullingPolicy* culling_ = nullptr; ///< policy_, when it culls
    const WorldSim* world_;
    int lookahead_ticks_;
    double cheapest_share_;
    bool started_ = false;
    std::vector<std::vector<interest::Interest>> answers_; ///< per client, reused
    interest::Hearing hearing_; ///< this tick's sounds (the server's rule, added to every policy)
};

/// The dsoc policies over a baked cell table (EvalOptions::bake_cell_size):
/// dsoc-baked (the table, then the exact stages) and dsoc-table (the table alone).
/// Not in all_policy_names(): the first run on a map bakes its table.
const std::vector<std::string>& baked_policy_names();

/// Every policy name, in report order.
[[nodiscard]] const std::vector<std::string>& all_policy_names();
/// Policies run only when named: "occlusion-k0", the occlusion policy with a
/// lookahead of 0 (a point region: the present eye), to see what the latency
/// allowance costs. Not conservative for moving viewers.
[[nodiscard]] const std::vector<std::string>& diagnostic_policy_names();

/// The policy `name` over `env` (which must outlive it); nullptr for an unknown name.
[[nodiscard]] std::unique_ptr<EvalPolicy> make_policy(std::string_view name, const PolicyEnv& env);

} // namespace dsoc::eval
