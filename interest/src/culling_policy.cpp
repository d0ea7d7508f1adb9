#include "dsoc/interest/culling_policy.hpp"

#include <algorithm>
#include <cassert>
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
    entity_teams_.clear();
    arrivals_.clear();
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
        manager().set_entity_team(e.id, e.team);
        scratch_.push_back(e.id);
        entity_teams_.push_back(e.team);
        if (e.arrival_eye) {
            arrivals_.emplace_back(e.id, *e.arrival_eye);
        }
    }
    while (k < known_entities_.size()) {
        manager().remove_entity(known_entities_[k++]);
    }
    known_entities_.swap(scratch_);
}

void CullingPolicy::sync_arrivals() {
    for (auto& [client, viewer] : viewers_) {
        // The viewer's team is its entity's (known_entities_ is this tick's, increasing).
        const auto self =
            std::lower_bound(known_entities_.begin(), known_entities_.end(), viewer.entity_id);
        const visibility::TeamId team =
            self != known_entities_.end() && *self == viewer.entity_id
                ? entity_teams_[static_cast<std::size_t>(self - known_entities_.begin())]
                : visibility::kNoTeam;
        manager().set_client_team(client, team);
        const auto arrival = std::lower_bound(arrivals_.begin(), arrivals_.end(), viewer.entity_id,
                                              [](const std::pair<std::uint32_t, glm::vec3>& a,
                                                 std::uint32_t id) { return a.first < id; });
        const bool arriving = arrival != arrivals_.end() && arrival->first == viewer.entity_id;
        const std::uint32_t spectator = client | kArrivalClientBit;
        if (arriving && !viewer.arriving) {
            visibility::ClientDesc desc = interest_.viewer();
            desc.viewer = visibility::kNoEntity; // a spectator: set_client_eye() places it
            manager().add_client(spectator, desc);
        } else if (!arriving && viewer.arriving) {
            manager().remove_client(spectator);
        }
        if (arriving) {
            manager().set_client_eye(spectator, arrival->second);
            manager().set_client_team(spectator, team);
        }
        viewer.arriving = arriving;
    }
}

void CullingPolicy::rebuild_client_index() {
    client_index_.clear();
    for (std::size_t i = 0; i < manager().client_count(); ++i) {
        client_index_[manager().client_at(i)] = i;
    }
}

void CullingPolicy::begin_tick(const WorldView& world, std::uint64_t tick) {
    interest_.begin_tick(tick, [&](visibility::InterestManager&) {
        sync_entities(world);
        sync_arrivals();
    });
    rebuild_client_index();
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
    const visibility::ClientDecisions* own = manager().decisions(viewer.client_id);
    if (own == nullptr) {
        return;
    }
    // update_interval 1, 2, 4 -> tier 0, 1, 2
    const auto tier_of = [](const visibility::Replicated& r) -> std::uint8_t {
        return r.update_interval >= 4 ? 2 : (r.update_interval >= 2 ? 1 : 0);
    };
    const auto arrival = client_index_.find(viewer.client_id | kArrivalClientBit);
    if (arrival == client_index_.end()) {
        for (const auto& r : own->replicated) {
            out.push_back({r.id, tier_of(r)});
        }
        return;
    }
    // A pending respawn: what the viewer sees now or from its arrival (both increasing
    // ids), each entity at the finer of its two tiers.
    manager().update_client(arrival->second, effort);
    const std::vector<visibility::Replicated>& a = own->replicated;
    const std::vector<visibility::Replicated>& b =
        manager().decisions(viewer.client_id | kArrivalClientBit)->replicated;
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < a.size() || j < b.size()) {
        if (j == b.size() || (i < a.size() && a[i].id < b[j].id)) {
            out.push_back({a[i].id, tier_of(a[i])});
            ++i;
        } else if (i == a.size() || b[j].id < a[i].id) {
            out.push_back({b[j].id, tier_of(b[j])});
            ++j;
        } else {
            out.push_back({a[i].id, std::min(tier_of(a[i]), tier_of(b[j]))});
            ++i;
            ++j;
        }
    }
}

void CullingPolicy::add_viewer(std::uint32_t client_id, std::uint32_t entity_id) {
    assert((client_id & kArrivalClientBit) == 0);
    if (interest_.add_viewer(client_id, entity_id)) {
        viewers_[client_id] = {entity_id, false};
    }
}

void CullingPolicy::remove_viewer(std::uint32_t client_id) {
    manager().remove_client(client_id);
    const auto viewer = viewers_.find(client_id);
    if (viewer != viewers_.end()) {
        if (viewer->second.arriving) {
            manager().remove_client(client_id | kArrivalClientBit);
        }
        viewers_.erase(viewer);
    }
    // The manager's indexes moved; keep the others' select() answering this tick.
    rebuild_client_index();
}

std::size_t CullingPolicy::tbvs_alive() const {
    std::size_t total = 0;
    for (std::size_t i = 0; i < manager().client_count(); ++i) {
        total += manager().tbv_count(manager().client_at(i));
    }
    return total;
}

} // namespace dsoc::interest
