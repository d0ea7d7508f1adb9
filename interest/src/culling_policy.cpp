#include "dsoc/interest/culling_policy.hpp"

#include <algorithm>
#include <utility>

namespace dsoc::interest {

CullingPolicy::CullingPolicy(std::string_view name, const visibility::DSOCConfig& config,
                             const maps::Map& map, const sim::MoveConfig& move,
                             visibility::RegionVisibilityFactory make_visibility,
                             int lookahead_ticks)
    : name_(name), interest_(config, map, move, std::move(make_visibility), lookahead_ticks) {}

void CullingPolicy::sync_entities(const WorldView& world) {
    // Entities are kept in increasing id order by the world; diff against ours.
    scratch_.clear();
    std::size_t k = 0;
    for (std::size_t i = 0; i < world.entity_count(); ++i) {
        const EntityView e = world.entity(i);
        while (k < known_entities_.size() && known_entities_[k] < e.id) {
            manager().remove_entity(known_entities_[k++]);
        }
        if (k < known_entities_.size() && known_entities_[k] == e.id) {
            ++k;
        } else {
            interest_.add_walker(e.id, e.box);
        }
        manager().set_entity_box(e.id, e.box, e.velocity);
        scratch_.push_back(e.id);
    }
    while (k < known_entities_.size()) {
        manager().remove_entity(known_entities_[k++]);
    }
    known_entities_.swap(scratch_);
}

void CullingPolicy::begin_tick(const WorldView& world, std::uint64_t tick) {
    interest_.begin_tick(tick, [&](visibility::InterestManager&) { sync_entities(world); });
    client_index_.clear();
    for (std::size_t i = 0; i < manager().client_count(); ++i) {
        client_index_[manager().client_at(i)] = i;
    }
}

void CullingPolicy::select(const WorldView& /*world*/, const Viewer& viewer,
                           std::vector<Interest>& out) {
    select_with(viewer, visibility::UpdateEffort::full, out);
}

void CullingPolicy::select_cheapest(const WorldView& /*world*/, const Viewer& viewer,
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
    manager().update_client(index->second, effort);
    if (const auto* d = manager().decisions(viewer.client_id)) {
        for (const auto& r : d->replicated) {
            // update_interval 1, 2, 4 -> tier 0, 1, 2
            const std::uint8_t tier = r.update_interval >= 4 ? 2 : (r.update_interval >= 2 ? 1 : 0);
            out.push_back({r.id, tier});
        }
    }
}

void CullingPolicy::add_viewer(std::uint32_t client_id, std::uint32_t entity_id) {
    interest_.add_viewer(client_id, entity_id);
}

void CullingPolicy::remove_viewer(std::uint32_t client_id) {
    manager().remove_client(client_id);
    // The manager's indexes moved; keep the others' select() answering this tick.
    client_index_.clear();
    for (std::size_t i = 0; i < manager().client_count(); ++i) {
        client_index_[manager().client_at(i)] = i;
    }
}

std::size_t CullingPolicy::tbvs_alive() const {
    std::size_t total = 0;
    for (std::size_t i = 0; i < manager().client_count(); ++i) {
        total += manager().tbv_count(manager().client_at(i));
    }
    return total;
}

} // namespace dsoc::interest
