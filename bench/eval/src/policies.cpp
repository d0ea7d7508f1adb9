#include "dsoc/eval/policies.hpp"

#include "dsoc/eval/frame_view.hpp"
#include "dsoc/interest/culler_stages.hpp"
#include "dsoc/interest/culling_policy.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <array>
#include <stdexcept>
#include <string>
#include <string_view>

namespace dsoc::eval {

namespace {

/// The server's culler (interest::PolicySettings' default culler: the exact shaft
/// stage without a per-region z-pyramid build).
visibility::RegionCullerConfig culler_config(bool fusion, int portal_depth) {
    visibility::RegionCullerConfig c;
    interest::set_culler_stages(interest::PolicySettings{}.culler, c);
    c.fusion = fusion;
    c.portal_depth = portal_depth;
    return c;
}

/// Which stages the culler of a culling policy runs, first to last.
enum class CullerStages {
    pvs_exact,   ///< the map's PVS, then the exact shaft stage
    baked_exact, ///< the baked table, the map's PVS, then the exact shaft stage
    baked_only,  ///< the baked table alone
};

interest::CullerStages stages_of(CullerStages stages, const PolicyEnv& env) {
    interest::CullerStages out;
    out.exact_config = culler_config(env.fusion, env.portal_depth);
    out.pvs = env.map->pvs;
    if (stages != CullerStages::pvs_exact) {
        out.table = env.table;
        out.exact = stages == CullerStages::baked_exact;
    }
    return out;
}

/// Per-pair Embree rays from the eye and from the eye extrapolated by the viewer's
/// velocity x latency (SMAC-style) to each box's 8 corners and centre. Over the
/// evaluation's frames, where entity i is at index i.
class RaycastPolicy final : public interest::InterestPolicy {
public:
    explicit RaycastPolicy(const PolicyEnv& env)
        : rays_(env.rays),
          latency_s_(static_cast<float>(env.scenario->rtt_ms + env.scenario->interpolation_ms) /
                     1000.0f) {}
    [[nodiscard]] std::string_view name() const override { return "raycast"; }

    void select(const interest::WorldView& world, const interest::Viewer& viewer,
                std::vector<interest::Interest>& out) override {
        out.clear();
        const glm::vec3 eye = viewer.eye;
        const glm::vec3 ahead = eye + world.entity(viewer.entity_id).velocity * latency_s_;
        std::array<glm::vec3, 9> points;
        for (std::size_t i = 0; i < world.entity_count(); ++i) {
            const interest::EntityView e = world.entity(i);
            if (e.id == viewer.entity_id) {
                continue;
            }
            const visibility::Aabb& box = e.box;
            if (visibility::team_relevance(viewer.team, e.team) == visibility::Relevance::always ||
                box.contains(eye)) {
                out.push_back({e.id, 0});
                continue;
            }
            points[0] = box.center();
            for (int c = 0; c < 8; ++c) {
                points[static_cast<std::size_t>(c) + 1] =
                    glm::vec3((c & 1) ? box.max.x : box.min.x, (c & 2) ? box.max.y : box.min.y,
                              (c & 4) ? box.max.z : box.min.z);
            }
            if (rays_->any_visible(eye, points) || rays_->any_visible(ahead, points)) {
                out.push_back({e.id, 0});
            }
        }
    }

private:
    const RayOracle* rays_;
    float latency_s_;
};

/// The culling policy `name` (interest::CullingPolicy) with `config` and `stages`.
std::unique_ptr<EvalPolicy> culling_policy(std::string_view name,
                                           const visibility::DSOCConfig& config,
                                           const PolicyEnv& env, int lookahead_ticks,
                                           CullerStages stages = CullerStages::pvs_exact) {
    auto policy = std::make_unique<interest::CullingPolicy>(
        name, config, *env.map, env.world->move(),
        interest::make_culler(env.scene, stages_of(stages, env)), lookahead_ticks);
    return std::make_unique<EvalPolicy>(std::move(policy), *env.world, lookahead_ticks,
                                        env.cheapest_share);
}

} // namespace

EvalPolicy::EvalPolicy(std::unique_ptr<interest::InterestPolicy> policy, const WorldSim& world,
                       int lookahead_ticks, double cheapest_share)
    : policy_(std::move(policy)),
      culling_(dynamic_cast<const interest::CullingPolicy*>(policy_.get())), world_(&world),
      lookahead_ticks_(lookahead_ticks), cheapest_share_(cheapest_share),
      answers_(world.viewer_count()) {}

void EvalPolicy::begin_tick(const WorldFrame& frame) {
    if (!started_) { // client c views from entity c
        for (std::uint32_t c = 0; c < world_->viewer_count(); ++c) {
            policy_->add_viewer(c, c);
        }
        started_ = true;
    }
    policy_->begin_tick(FrameView(frame), frame.tick);
    hearing_.begin_tick(FrameView(frame));
}

void EvalPolicy::select(std::size_t client, const WorldFrame& frame,
                        std::vector<std::uint32_t>& out, std::vector<std::uint32_t>& heard) {
    interest::Viewer viewer;
    viewer.client_id = static_cast<std::uint32_t>(client);
    viewer.entity_id = static_cast<std::uint32_t>(client);
    viewer.eye = world_->eye(frame, client);
    viewer.arrival_eye = frame.entities[client].arrival_eye;
    viewer.team = frame.entities[client].team;
    std::vector<interest::Interest>& answer = answers_[client];
    const FrameView view(frame);
    if (over_budget(client, frame.tick)) {
        policy_->select_cheapest(view, viewer, answer);
    } else {
        policy_->select(view, viewer, answer);
    }
    hearing_.add_heard(viewer, *policy_, answer);
    out.clear();
    heard.clear();
    for (const interest::Interest& wanted : answer) {
        if (wanted.id != client) {
            out.push_back(wanted.id);
            if (wanted.tier == interest::kHeardTier) {
                heard.push_back(wanted.id);
            }
        }
    }
}

bool EvalPolicy::over_budget(std::size_t client, std::uint64_t tick) const {
    if (cheapest_share_ <= 0.0) {
        return false;
    }
    std::uint64_t z = tick << 32 ^ client;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53 < cheapest_share_;
}

TbvSummary EvalPolicy::tbv_summary() const {
    TbvSummary t;
    if (culling_ == nullptr) {
        return t;
    }
    t.available = true;
    const visibility::InterestManager& manager = culling_->manager();
    for (std::uint32_t c = 0; c < world_->viewer_count(); ++c) {
        const auto* s = manager.stats(c);
        if (s == nullptr) {
            continue;
        }
        t.buffer_builds += s->buffer_builds;
        t.box_tests += s->box_tests;
        t.tbv_tests += s->tbv_tests;
        t.cluster_tests += s->cluster_tests;
        t.cluster_hits += s->cluster_hits;
        t.tbvs_created += s->tbvs_created;
        t.tbvs_merged += s->tbvs_merged;
        t.tbvs_rejected += s->tbvs_rejected;
        t.tbv_hits += s->tbv_hits;
        t.tbvs_expired += s->tbvs_expired;
        t.evictions += s->evictions;
        t.teleports += s->teleports;
        t.cheapest_updates += s->cheapest_updates;
        t.fuzzy_escapes += s->fuzzy_escapes;
    }
    return t;
}

const std::vector<std::string>& diagnostic_policy_names() {
    static const std::vector<std::string> names = {"occlusion-k0"};
    return names;
}

const std::vector<std::string>& baked_policy_names() {
    static const std::vector<std::string> names = {"dsoc-baked", "dsoc-table"};
    return names;
}

const std::vector<std::string>& all_policy_names() {
    static const std::vector<std::string> names = {"broadcast",     "distance",   "pvs",
                                                   "occlusion",     "dsoc",       "dsoc-tbvs",
                                                   "dsoc-explicit", "dsoc-fuzzy", "raycast"};
    return names;
}

std::unique_ptr<EvalPolicy> make_policy(std::string_view name, const PolicyEnv& env) {
    const auto unculled = [&env](std::unique_ptr<interest::InterestPolicy> policy) {
        return std::make_unique<EvalPolicy>(std::move(policy), *env.world, 0);
    };
    if (name == "broadcast") {
        return unculled(std::make_unique<interest::BroadcastPolicy>());
    }
    if (name == "distance") {
        return unculled(std::make_unique<interest::DistancePolicy>(env.scenario->distance_radius));
    }
    if (name == "raycast") {
        return unculled(std::make_unique<RaycastPolicy>(env));
    }
    if (name == "pvs") {
        return unculled(std::make_unique<interest::PvsPolicy>(env.map->pvs));
    }
    visibility::DSOCConfig config;
    config.tick_rate = env.scenario->tick_rate;
    if (name == "occlusion" || name == "occlusion-k0") { // every box, every tick
        interest::apply_policy_presets(interest::PolicyKind::occlusion, config);
        if (name == "occlusion-k0") { // diagnostic: the present eye only
            return culling_policy(name, config, env, 0);
        }
    } else if (name == "dsoc" || name == "dsoc-baked" || name == "dsoc-table") {
        config.strategy = visibility::TbvStrategy::adaptive;
    } else if (name == "dsoc-tbvs") { // the defaults with the paper's TBVs on
        config.strategy = visibility::TbvStrategy::adaptive;
        config.tbvs_enabled = true;
    } else if (name == "dsoc-explicit") {
        config.strategy = visibility::TbvStrategy::explicit_duration;
        config.tbvs_enabled = true;
    } else if (name == "dsoc-fuzzy") {
        config.strategy = visibility::TbvStrategy::fuzzy;
        config.tbvs_enabled = true;
    } else {
        return nullptr;
    }
    config.entity_cluster_size = env.entity_cluster_size;
    if (name != "occlusion" && env.dsoc_overrides != nullptr) { // --dsoc-set KEY=VALUE
        for (const std::string& setting : *env.dsoc_overrides) {
            const std::size_t eq = setting.find('=');
            const std::string error =
                eq == std::string::npos
                    ? "expected KEY=VALUE"
                    : visibility::set_field(config, std::string_view(setting).substr(0, eq),
                                            std::string_view(setting).substr(eq + 1));
            if (!error.empty()) {
                throw std::runtime_error("--dsoc-set " + setting + ": " + error);
            }
        }
    }
    if (const auto problems = visibility::validate(config); !problems.empty()) {
        throw std::runtime_error("DSOCConfig for " + std::string(name) + ": " + problems.front());
    }
    CullerStages stages = CullerStages::pvs_exact;
    if (name == "dsoc-baked" || name == "dsoc-table") {
        if (env.table == nullptr) {
            throw std::runtime_error(std::string(name) + " needs a baked table (--bake-cell-size)");
        }
        stages = name == "dsoc-baked" ? CullerStages::baked_exact : CullerStages::baked_only;
    }
    return culling_policy(name, config, env, env.lookahead_ticks, stages);
}

} // namespace dsoc::eval
