#include "dsoc/eval/policies.hpp"

#include "dsoc/interest/culler_stages.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/interest/walking_interest.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <array>
#include <stdexcept>
#include <string>
#include <string_view>

namespace dsoc::eval {

namespace {

class BroadcastPolicy final : public Policy {
public:
    [[nodiscard]] std::string_view name() const override { return "broadcast"; }
    void select(std::size_t client, const WorldFrame& frame,
                std::vector<std::uint32_t>& out) override {
        out.clear();
        for (std::uint32_t id = 0; id < frame.entities.size(); ++id) {
            if (id != client) {
                out.push_back(id);
            }
        }
    }
};

/// interest::DistancePolicy's rule (interest::within_radius()) over the eval's frames.
class DistancePolicy final : public Policy {
public:
    DistancePolicy(const WorldSim& world, float radius) : world_(&world), radius_(radius) {}
    [[nodiscard]] std::string_view name() const override { return "distance"; }
    void select(std::size_t client, const WorldFrame& frame,
                std::vector<std::uint32_t>& out) override {
        out.clear();
        const glm::vec3 eye = world_->eye(frame, client);
        for (std::uint32_t id = 0; id < frame.entities.size(); ++id) {
            if (id != client && interest::within_radius(frame.entities[id].box, eye, radius_)) {
                out.push_back(id);
            }
        }
    }

private:
    const WorldSim* world_;
    float radius_;
};

/// What the Quake 3 server does: interest::PvsPolicy's rule (interest::eye_pvs_rows(),
/// maps::Pvs::may_see()) over the eval's frames, the viewer's own entity left out.
class PvsPolicy final : public Policy {
public:
    PvsPolicy(const WorldSim& world, std::shared_ptr<const maps::Pvs> pvs)
        : world_(&world), pvs_(std::move(pvs)) {}
    [[nodiscard]] std::string_view name() const override { return "pvs"; }
    void select(std::size_t client, const WorldFrame& frame,
                std::vector<std::uint32_t>& out) override {
        out.clear();
        // select() runs for several clients at once: scratch is per call.
        std::vector<std::int32_t> clusters;
        std::vector<std::int32_t> scratch;
        std::vector<std::uint8_t> rows;
        const bool known =
            interest::eye_pvs_rows(pvs_.get(), world_->eye(frame, client), clusters, rows);
        for (std::uint32_t id = 0; id < frame.entities.size(); ++id) {
            if (id != client && (!known || pvs_->may_see(rows, frame.entities[id].box, scratch))) {
                out.push_back(id);
            }
        }
    }

private:
    const WorldSim* world_;
    std::shared_ptr<const maps::Pvs> pvs_;
};

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

class CullingPolicy final : public Policy {
public:
    CullingPolicy(std::string name, const visibility::DSOCConfig& config, const PolicyEnv& env,
                  CullerStages stages = CullerStages::pvs_exact)
        : name_(std::move(name)), lookahead_(env.lookahead_ticks),
          cheapest_share_(env.cheapest_share),
          interest_(config, *env.map, env.world->move(),
                    interest::make_culler(env.scene, stages_of(stages, env)), env.lookahead_ticks),
          viewers_(env.world->viewer_count()) {}

    [[nodiscard]] std::string_view name() const override { return name_; }
    [[nodiscard]] int lookahead_ticks() const override { return lookahead_; }

    void begin_tick(const WorldFrame& frame) override {
        interest_.begin_tick(frame.tick, [&](visibility::InterestManager& manager) {
            if (!started_) {
                add_everyone(frame);
            }
            for (std::uint32_t id = 0; id < frame.entities.size(); ++id) {
                manager.set_entity_box(id, frame.entities[id].box, frame.entities[id].velocity);
            }
        });
    }

    void select(std::size_t client, const WorldFrame& frame,
                std::vector<std::uint32_t>& out) override {
        // Clients were added in order, so index i is client i.
        manager().update_client(client, over_budget(client, frame.tick)
                                            ? visibility::UpdateEffort::cheapest
                                            : visibility::UpdateEffort::full);
        out.clear();
        if (const auto* d = manager().decisions(static_cast<visibility::ClientId>(client))) {
            for (const auto& r : d->replicated) {
                if (r.id != client) {
                    out.push_back(r.id);
                }
            }
        }
    }

    [[nodiscard]] TbvSummary tbv_summary() const override {
        TbvSummary t;
        t.available = true;
        for (std::uint32_t c = 0; c < viewers_; ++c) {
            const auto* s = manager().stats(c);
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

    [[nodiscard]] std::uint64_t live_tbvs() const override {
        std::uint64_t n = 0;
        for (std::uint32_t c = 0; c < viewers_; ++c) {
            n += manager().tbv_count(c);
        }
        return n;
    }

private:
    /// Whether this client-tick is one of the emulated overload's (cheapest_share_ of
    /// them, chosen by a hash: the same in every run and at any thread count).
    [[nodiscard]] bool over_budget(std::size_t client, std::uint64_t tick) const {
        if (cheapest_share_ <= 0.0) {
            return false;
        }
        std::uint64_t z = tick << 32 ^ client;
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        z ^= z >> 31;
        return static_cast<double>(z >> 11) * 0x1.0p-53 < cheapest_share_;
    }

    void add_everyone(const WorldFrame& frame) {
        for (std::uint32_t id = 0; id < frame.entities.size(); ++id) {
            if (!interest_.add_walker(id, frame.entities[id].box)) {
                throw std::runtime_error("InterestManager refused entity " + std::to_string(id));
            }
        }
        for (std::uint32_t c = 0; c < viewers_; ++c) {
            if (!interest_.add_viewer(c, c)) {
                throw std::runtime_error("InterestManager refused client " + std::to_string(c));
            }
        }
        started_ = true;
    }

    [[nodiscard]] visibility::InterestManager& manager() { return interest_.manager(); }
    [[nodiscard]] const visibility::InterestManager& manager() const { return interest_.manager(); }

    std::string name_;
    int lookahead_;
    double cheapest_share_;
    interest::WalkingInterest interest_;
    std::size_t viewers_ = 0;
    bool started_ = false;
};

class RaycastPolicy final : public Policy {
public:
    RaycastPolicy(const PolicyEnv& env)
        : world_(env.world), rays_(env.rays),
          latency_s_(static_cast<float>(env.scenario->rtt_ms + env.scenario->interpolation_ms) /
                     1000.0f) {}
    [[nodiscard]] std::string_view name() const override { return "raycast"; }

    void select(std::size_t client, const WorldFrame& frame,
                std::vector<std::uint32_t>& out) override {
        out.clear();
        const glm::vec3 eye = world_->eye(frame, client);
        const glm::vec3 ahead = eye + frame.entities[client].velocity * latency_s_;
        std::array<glm::vec3, 9> points;
        for (std::uint32_t id = 0; id < frame.entities.size(); ++id) {
            if (id == client) {
                continue;
            }
            const visibility::Aabb& box = frame.entities[id].box;
            if (box.contains(eye)) {
                out.push_back(id);
                continue;
            }
            points[0] = box.center();
            for (int c = 0; c < 8; ++c) {
                points[static_cast<std::size_t>(c) + 1] =
                    glm::vec3((c & 1) ? box.max.x : box.min.x, (c & 2) ? box.max.y : box.min.y,
                              (c & 4) ? box.max.z : box.min.z);
            }
            if (rays_->any_visible(eye, points) || rays_->any_visible(ahead, points)) {
                out.push_back(id);
            }
        }
    }

private:
    const WorldSim* world_;
    const RayOracle* rays_;
    float latency_s_;
};

} // namespace

const std::vector<std::string>& diagnostic_policy_names() {
    static const std::vector<std::string> names = {"occlusion-k0"};
    return names;
}

const std::vector<std::string>& baked_policy_names() {
    static const std::vector<std::string> names = {"dsoc-baked", "dsoc-table"};
    return names;
}

const std::vector<std::string>& all_policy_names() {
    static const std::vector<std::string> names = {"broadcast",  "distance", "pvs",
                                                   "occlusion",  "dsoc",     "dsoc-explicit",
                                                   "dsoc-fuzzy", "raycast"};
    return names;
}

std::unique_ptr<Policy> make_policy(std::string_view name, const PolicyEnv& env) {
    if (name == "broadcast") {
        return std::make_unique<BroadcastPolicy>();
    }
    if (name == "distance") {
        return std::make_unique<DistancePolicy>(*env.world, env.scenario->distance_radius);
    }
    if (name == "raycast") {
        return std::make_unique<RaycastPolicy>(env);
    }
    if (name == "pvs") {
        return std::make_unique<PvsPolicy>(*env.world, env.map->pvs);
    }
    visibility::DSOCConfig config;
    config.tick_rate = env.scenario->tick_rate;
    PolicyEnv point_env = env;
    if (name == "occlusion" || name == "occlusion-k0") { // every box, every tick
        interest::apply_policy_presets(interest::PolicyKind::occlusion, config);
        if (name == "occlusion-k0") {
            point_env.lookahead_ticks = 0; // diagnostic: the present eye only
            return std::make_unique<CullingPolicy>(std::string(name), config, point_env);
        }
    } else if (name == "dsoc" || name == "dsoc-baked" || name == "dsoc-table") {
        config.strategy = visibility::TbvStrategy::adaptive;
    } else if (name == "dsoc-explicit") {
        config.strategy = visibility::TbvStrategy::explicit_duration;
    } else if (name == "dsoc-fuzzy") {
        config.strategy = visibility::TbvStrategy::fuzzy;
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
    return std::make_unique<CullingPolicy>(std::string(name), config, env, stages);
}

} // namespace dsoc::eval
