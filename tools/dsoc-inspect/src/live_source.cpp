#include "dsoc/inspect/live_source.hpp"

#include "dsoc/interest/culling_policy.hpp"

#include <stdexcept>

namespace dsoc::inspect {

namespace {

interest::WorldSettings world_settings(const LiveOptions& o) {
    interest::WorldSettings s;
    s.bots = o.bots;
    s.seed = o.seed;
    // As the server: the shortest delay that keeps respawns from popping entities in.
    s.respawn_delay_ticks = interest::lookahead_ticks(o.latency_allowance_ms, o.tick_rate);
    return s;
}

/// The server's policy settings for these options (its defaults for the rest).
interest::PolicySettings policy_settings(const LiveOptions& o) {
    interest::PolicySettings s;
    s.policy = o.policy;
    s.dsoc.tick_rate = o.tick_rate;
    interest::apply_policy_presets(o.policy, s.dsoc);
    s.dsoc.tbvs_enabled = o.tbvs; // validate(): only with dsoc
    s.culler = o.culler;
    s.lookahead_ticks = interest::lookahead_ticks(o.latency_allowance_ms, o.tick_rate);
    // The exact stages, as the classifier below: the pictures show what the PVS and
    // shaft stages decide, and the TBVs with --tbvs (behind the baked table there are none).
    s.baked_stage = false;
    return s;
}

visibility::RegionCullerConfig culler_config(interest::CullerKind culler) {
    visibility::RegionCullerConfig c;
    interest::set_culler_stages(culler, c); // as interest::make_policy reads it
    return c;
}

} // namespace

std::vector<std::string> validate(const LiveOptions& o) {
    std::vector<std::string> problems;
    if (o.policy != interest::PolicyKind::dsoc && o.policy != interest::PolicyKind::occlusion) {
        problems.push_back("policy '" + std::string(interest::name_of(o.policy)) +
                           "': the inspector shows the culling policies, dsoc or occlusion");
    }
    if (o.tbvs && o.policy != interest::PolicyKind::dsoc) {
        problems.push_back("tbvs with policy '" + std::string(interest::name_of(o.policy)) +
                           "': only dsoc has TBVs");
    }
    // The settings interest::make_policy and GameWorld read, with the server's limits
    // (ServerConfig's validate()).
    if (o.bots < 1 || o.bots > 100000) {
        problems.push_back("bots " + std::to_string(o.bots) + ": must be 1..100000");
    }
    if (o.tick_rate < 1 || o.tick_rate > 240) {
        problems.push_back("tick rate " + std::to_string(o.tick_rate) + ": must be 1..240 Hz");
    }
    if (o.latency_allowance_ms < 0 || o.latency_allowance_ms > 2000) {
        problems.push_back("latency allowance " + std::to_string(o.latency_allowance_ms) +
                           ": must be 0..2000 ms");
    }
    if (o.viewer_entity < 1 || o.bots < 1 || o.viewer_entity > static_cast<std::uint32_t>(o.bots)) {
        problems.push_back("client " + std::to_string(o.viewer_entity) +
                           ": the client views from a bot, 1.." + std::to_string(o.bots));
    }
    return problems;
}

LiveSimulation::LiveSimulation(std::shared_ptr<const maps::Map> map, const LiveOptions& options)
    : map_(std::move(map)), options_(options) {
    if (const auto problems = validate(options); !problems.empty()) {
        std::string all;
        for (const auto& p : problems) {
            all += (all.empty() ? "" : "; ") + p;
        }
        throw std::invalid_argument(all);
    }
    if (map_ == nullptr || map_->spawn_points.empty()) {
        throw std::invalid_argument("map: the live simulation needs a map with spawn points");
    }
    world_ = std::make_unique<interest::GameWorld>(world_settings(options), map_);
    policy_ = interest::make_policy(policy_settings(options), *world_);
    culling_ = dynamic_cast<const interest::CullingPolicy*>(policy_.get());
    if (culling_ == nullptr) {
        throw std::logic_error("interest::make_policy did not return a CullingPolicy for " +
                               std::string(interest::name_of(options.policy)));
    }
    policy_->add_viewer(kClientId, options.viewer_entity);
    scene_ = visibility::OccluderScene::build(map_->occluders);
    // As interest::make_policy: the map's PVS stage in front of the occluder culler.
    classifier_ =
        std::make_unique<ReplicatedClassifier>(scene_, map_->pvs, culler_config(options.culler));
}

LiveSimulation::~LiveSimulation() = default;

void LiveSimulation::advance() {
    world_->step(1.0f / static_cast<float>(options_.tick_rate));
    ++tick_;
    policy_->begin_tick(*world_, tick_);
    // The policy decides for a viewer in begin_tick() or in select(), depending on how
    // the server spreads per-client work; ask, as the server does, so both hold.
    if (const interest::Entity* self = world_->find(options_.viewer_entity)) {
        const interest::Viewer viewer = interest::viewer_of(*world_, kClientId, *self);
        std::vector<interest::Interest> answer;
        policy_->select(*world_, viewer, answer);
        // And what the viewer hears, as the server adds it.
        hearing_.begin_tick(*world_);
        hearing_.add_heard(viewer, *policy_, answer);
        heard_.clear();
        for (const interest::Interest& i : answer) {
            if (i.tier == interest::kHeardTier) {
                heard_.push_back(i.id);
            }
        }
    }
}

ClientView LiveSimulation::view() {
    const visibility::InterestManager& manager = culling_->manager();
    ClientView v;
    v.tick = tick_;
    v.client = kClientId;
    v.viewer_entity = options_.viewer_entity;
    const interest::Entity* self = world_->find(options_.viewer_entity);
    if (self != nullptr) {
        v.eye = world_->eye_of(*self);
        v.viewer_box = world_->box_of(*self);
    }
    v.eye_region = manager.eye_region(kClientId);
    classifier_->prepare(v.eye, v.eye_region);
    std::vector<bool> replicated;
    if (const auto* d = manager.decisions(kClientId)) {
        for (const auto& r : d->replicated) {
            if (r.id >= replicated.size()) {
                replicated.resize(r.id + 1, false);
            }
            replicated[r.id] = true;
        }
    }
    for (const interest::Entity& e : world_->entities()) {
        if (e.id == options_.viewer_entity) {
            continue;
        }
        EntityView ev;
        ev.id = e.id;
        ev.box = world_->box_of(e);
        if (std::binary_search(heard_.begin(), heard_.end(), e.id)) {
            ev.state = EntityState::replicated_heard;
        } else if (e.id < replicated.size() && replicated[e.id]) {
            ev.state = manager.relevance(kClientId, e.id) == visibility::Relevance::always
                           ? EntityState::replicated_rule
                           : classifier_->classify(ev.box);
        } else {
            switch (manager.state(kClientId, e.id)) {
            case visibility::PairState::hidden_with_tbv:
                ev.state = EntityState::hidden_tbv;
                ev.tbv = manager.tbv_of(kClientId, e.id);
                break;
            case visibility::PairState::hidden_expired:
                ev.state = EntityState::hidden_expired;
                break;
            case visibility::PairState::visible: // not in the set: cannot happen
            case visibility::PairState::unknown:
                ev.state = EntityState::not_replicated;
                break;
            }
        }
        v.entities.push_back(ev);
    }
    return v;
}

} // namespace dsoc::inspect
