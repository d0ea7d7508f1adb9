#include "dsoc/server/culling_policy.hpp"

#include "dsoc/sim/motion_limits.hpp"

#include <algorithm>
#include <string>

namespace dsoc::server {

CullingPolicy::CullingPolicy(std::string_view name, const visibility::DSOCConfig& config,
                             const GameWorld& world,
                             visibility::RegionVisibilityFactory make_visibility,
                             int lookahead_ticks)
    : name_(name), clipper_(std::make_shared<const sim::ReachClipper>(world.map().collision_brushes,
                                                                      world.move_config())),
      manager_(config, world.map().bounds.expanded(64.0f), std::move(make_visibility),
               [clipper = clipper_](glm::vec3 eye, const visibility::Aabb& region,
                                    const visibility::EyeReach& reach) {
                   return clipper->clip(eye, region, reach);
               }) {
    const auto& move = world.move_config();
    entity_desc_.half_extents = (move.maxs - move.mins) * 0.5f;
    entity_desc_.motion = sim::walking_limits(move, 1.0f / static_cast<float>(config.tick_rate));
    client_desc_.eye_motion = entity_desc_.motion;
    client_desc_.lookahead_ticks = lookahead_ticks;
    // The manager's eye is the box centre plus this offset.
    client_desc_.eye_offset =
        glm::vec3(0.0f, 0.0f, move.eye_height - (move.mins.z + move.maxs.z) * 0.5f);
}

void CullingPolicy::sync_entities(const GameWorld& world) {
    // Entities are kept in increasing id order by the world; diff against ours.
    scratch_.clear();
    std::size_t k = 0;
    for (const Entity& e : world.entities()) {
        while (k < known_entities_.size() && known_entities_[k] < e.id) {
            manager_.remove_entity(known_entities_[k++]);
        }
        const visibility::Aabb box = world.box_of(e);
        if (k < known_entities_.size() && known_entities_[k] == e.id) {
            ++k;
            manager_.set_entity_box(e.id, box, e.move.velocity);
        } else {
            manager_.add_entity(e.id, entity_desc_, box);
            manager_.set_entity_box(e.id, box, e.move.velocity);
        }
        scratch_.push_back(e.id);
    }
    while (k < known_entities_.size()) {
        manager_.remove_entity(known_entities_[k++]);
    }
    known_entities_.swap(scratch_);
}

void CullingPolicy::begin_tick(const GameWorld& world, std::uint64_t tick) {
    // ValidateDSOCState of the last tick, once every client has been updated.
    if (manager_.config().validate_state) {
        manager_.require_valid_state("before tick " + std::to_string(tick));
    }
    sync_entities(world);
    manager_.begin_update(tick);
    client_index_.clear();
    for (std::size_t i = 0; i < manager_.client_count(); ++i) {
        client_index_[manager_.client_at(i)] = i;
    }
}

void CullingPolicy::select(const GameWorld& /*world*/, const Viewer& viewer,
                           std::vector<Interest>& out) {
    select_with(viewer, visibility::UpdateEffort::full, out);
}

void CullingPolicy::select_cheapest(const GameWorld& /*world*/, const Viewer& viewer,
                                    std::vector<Interest>& out) {
    select_with(viewer, visibility::UpdateEffort::cheapest, out);
}

void CullingPolicy::select_with(const Viewer& viewer, visibility::UpdateEffort effort,
                                std::vector<Interest>& out) {
    out.clear();
    const auto index = client_index_.find(viewer.client_id);
    if (index == client_index_.end()) {
        return; // joined after begin_tick(): first decisions next tick
    }
    manager_.update_client(index->second, effort);
    if (const auto* d = manager_.decisions(viewer.client_id)) {
        for (const auto& r : d->replicated) {
            // update_interval 1, 2, 4 -> tier 0, 1, 2
            const std::uint8_t tier = r.update_interval >= 4 ? 2 : (r.update_interval >= 2 ? 1 : 0);
            out.push_back({r.id, tier});
        }
    }
}

void CullingPolicy::add_viewer(std::uint32_t client_id, std::uint32_t entity_id) {
    auto desc = client_desc_;
    desc.viewer = entity_id;
    manager_.add_client(client_id, desc);
}

void CullingPolicy::remove_viewer(std::uint32_t client_id) {
    manager_.remove_client(client_id);
    // The manager's indexes moved; keep the others' select() answering this tick.
    client_index_.clear();
    for (std::size_t i = 0; i < manager_.client_count(); ++i) {
        client_index_[manager_.client_at(i)] = i;
    }
}

std::size_t CullingPolicy::tbvs_alive() const {
    std::size_t total = 0;
    for (std::size_t i = 0; i < manager_.client_count(); ++i) {
        total += manager_.tbv_count(manager_.client_at(i));
    }
    return total;
}

} // namespace dsoc::server
