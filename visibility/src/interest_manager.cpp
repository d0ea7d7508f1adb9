// InterestManager: construction, the registry of entities and clients, and the
// queries on them. The private state, and which file does which job, are in
// interest_manager_state.hpp.

#include "interest_manager_state.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

namespace dsoc::visibility {

using detail::kNoGroup;
using detail::valid_box;

const char* to_string(PairState s) noexcept {
    switch (s) {
    case PairState::unknown:
        return "unknown";
    case PairState::visible:
        return "visible";
    case PairState::hidden_with_tbv:
        return "hidden_with_tbv";
    case PairState::hidden_expired:
        return "hidden_expired";
    }
    return "invalid";
}

InterestManager::InterestManager(const DSOCConfig& config, const Aabb& world_bounds,
                                 RegionVisibilityFactory make_visibility, EyeRegionClipper clipper)
    : config_(config), world_bounds_(world_bounds), make_visibility_(std::move(make_visibility)),
      clipper_(std::move(clipper)), tick_seconds_(1.0f / static_cast<float>(config.tick_rate)) {
    if (const auto problems = validate(config_); !problems.empty()) {
        throw std::invalid_argument("DSOCConfig: " + problems.front());
    }
    if (make_visibility_) {
        preparer_ = make_visibility_();
        prepared_stage_ = preparer_ != nullptr && preparer_->has_prepared_stage();
    }
    const bool shortcuts_pay = preparer_ == nullptr || preparer_->pair_shortcuts_pay();
    tbvs_enabled_ = config_.tbvs_enabled && shortcuts_pay;
    clusters_enabled_ = config_.entity_cluster_size > 0.0f && shortcuts_pay;
}

InterestManager::~InterestManager() = default;

// ---- entities --------------------------------------------------------------------

bool InterestManager::add_entity(EntityId id, const EntityDesc& desc, const Aabb& box) {
    if (id == kNoEntity || entity_slot_.contains(id) || !valid_box(box)) {
        return false;
    }
    std::uint32_t slot;
    auto& counts = tbv_counts_;
    if (!free_entity_slots_.empty()) {
        slot = free_entity_slots_.back();
        free_entity_slots_.pop_back();
    } else {
        slot = static_cast<std::uint32_t>(entities_.size());
        entities_.emplace_back();
        views_.emplace_back();
        view_alive_.emplace_back(0);
        view_fresh_.emplace_back(0);
        view_team_.emplace_back(kNoTeam);
        counts.emplace_back(0);
        for (auto& c : clients_) {
            c->pairs.resize(entities_.size());
            c->hints.resize(entities_.size(), 0);
            c->states.resize(entities_.size(), PairState::unknown);
            c->rules.resize(entities_.size(), 0);
        }
        // The slots may have moved: the packed boxes of this tick point at them again.
        for (std::size_t i = 0; i < packed_boxes_.size(); ++i) {
            if (packed_boxes_.boxes[i] != nullptr) {
                packed_boxes_.boxes[i] = &entities_[i].prepared;
            }
        }
    }
    EntitySlot& e = entities_[slot];
    e = EntitySlot{};
    e.id = id;
    e.alive = true;
    e.desc = desc;
    e.box = box;
    e.box_at_last_update = box;
    views_[slot] = {box, id};
    view_alive_[slot] = 1;
    view_fresh_[slot] = e.prepared_is_current() ? 1 : 0;
    view_team_[slot] = kNoTeam;
    counts[slot].store(0);
    entity_slot_[id] = slot;
    return true;
}

bool InterestManager::remove_entity(EntityId id) {
    const auto it = entity_slot_.find(id);
    if (it == entity_slot_.end()) {
        return false;
    }
    const std::uint32_t slot = it->second;
    for (auto& c : clients_) {
        if (c->states[slot] == PairState::hidden_with_tbv) {
            release_group_member(*c, slot);
        }
        c->pairs[slot] = {};
        c->hints[slot] = 0;
        c->states[slot] = PairState::unknown;
        c->rules[slot] = 0;
    }
    entities_[slot].alive = false;
    view_alive_[slot] = 0;
    view_fresh_[slot] = 0;
    entity_slot_.erase(it);
    free_entity_slots_.push_back(slot);
    return true;
}

bool InterestManager::set_entity_box(EntityId id, const Aabb& box, glm::vec3 velocity) {
    const auto it = entity_slot_.find(id);
    if (it == entity_slot_.end() || !valid_box(box)) {
        return false;
    }
    EntitySlot& e = entities_[it->second];
    e.box = box;
    views_[it->second].box = box;
    view_fresh_[it->second] = e.prepared_is_current() ? 1 : 0;
    e.down_velocity = std::isfinite(velocity.z) ? std::max(0.0f, -velocity.z) : -1.0f;
    return true;
}

// ---- clients ---------------------------------------------------------------------

bool InterestManager::add_client(ClientId id, const ClientDesc& desc) {
    if (client_index_.contains(id)) {
        return false;
    }
    LooseOctreeConfig tree_config;
    tree_config.world_bounds = world_bounds_;
    tree_config.max_items = static_cast<std::uint32_t>(config_.max_tbvs_per_client);
    auto slot = std::make_unique<ClientSlot>(id, desc, tree_config, make_visibility_());
    slot->pairs.resize(entities_.size());
    slot->hints.resize(entities_.size(), 0);
    slot->states.resize(entities_.size(), PairState::unknown);
    slot->rules.resize(entities_.size(), 0);
    slot->groups.reserve(static_cast<std::size_t>(std::min(config_.max_tbvs_per_client, 1024)));
    client_index_[id] = clients_.size();
    clients_.push_back(std::move(slot));
    return true;
}

bool InterestManager::remove_client(ClientId id) {
    const auto it = client_index_.find(id);
    if (it == client_index_.end()) {
        return false;
    }
    const std::size_t index = it->second;
    ClientSlot& c = *clients_[index];
    auto& counts = tbv_counts_;
    for (std::size_t slot = 0; slot < c.states.size(); ++slot) {
        if (c.states[slot] == PairState::hidden_with_tbv) {
            counts[slot].fetch_sub(1, std::memory_order_relaxed);
        }
    }
    client_index_.erase(it);
    if (index + 1 != clients_.size()) {
        clients_[index] = std::move(clients_.back());
        client_index_[clients_[index]->id] = index;
    }
    clients_.pop_back();
    return true;
}

bool InterestManager::set_client_eye(ClientId id, glm::vec3 eye) {
    const auto it = client_index_.find(id);
    if (it == client_index_.end() || !std::isfinite(eye.x) || !std::isfinite(eye.y) ||
        !std::isfinite(eye.z)) {
        return false;
    }
    clients_[it->second]->spectator_eye = eye;
    clients_[it->second]->has_spectator_eye = true;
    return true;
}

bool InterestManager::set_entity_team(EntityId id, TeamId team) {
    const auto it = entity_slot_.find(id);
    if (it == entity_slot_.end()) {
        return false;
    }
    view_team_[it->second] = team;
    return true;
}

bool InterestManager::set_client_team(ClientId id, TeamId team) {
    const auto it = client_index_.find(id);
    if (it == client_index_.end()) {
        return false;
    }
    clients_[it->second]->team = team;
    return true;
}

bool InterestManager::set_relevance(ClientId client, EntityId entity,
                                    std::optional<Relevance> rule) {
    const auto c = client_index_.find(client);
    const auto e = entity_slot_.find(entity);
    if (c == client_index_.end() || e == entity_slot_.end() ||
        clients_[c->second]->desc.viewer == entity) {
        return false;
    }
    clients_[c->second]->rules[e->second] =
        rule ? static_cast<std::uint8_t>(1 + static_cast<std::uint8_t>(*rule)) : 0;
    return true;
}

Relevance InterestManager::relevance(ClientId client, EntityId entity) const {
    const auto c = client_index_.find(client);
    const auto e = entity_slot_.find(entity);
    if (c == client_index_.end() || e == entity_slot_.end()) {
        return Relevance::sight;
    }
    return rule_of(*clients_[c->second], e->second);
}

ClientId InterestManager::client_at(std::size_t index) const {
    return clients_[index]->id;
}

const ClientDecisions* InterestManager::decisions(ClientId id) const {
    const auto it = client_index_.find(id);
    return it == client_index_.end() ? nullptr : &clients_[it->second]->decisions;
}

const ClientStats* InterestManager::stats(ClientId id) const {
    const auto it = client_index_.find(id);
    return it == client_index_.end() ? nullptr : &clients_[it->second]->stats;
}

PairState InterestManager::state(ClientId client, EntityId entity) const {
    const auto c = client_index_.find(client);
    const auto e = entity_slot_.find(entity);
    if (c == client_index_.end() || e == entity_slot_.end()) {
        return PairState::unknown;
    }
    return clients_[c->second]->states[e->second];
}

Aabb InterestManager::eye_region(ClientId id) const {
    const auto it = client_index_.find(id);
    return it == client_index_.end() ? Aabb{} : clients_[it->second]->region;
}

Aabb InterestManager::tbv_of(ClientId client, EntityId entity) const {
    const auto c = client_index_.find(client);
    const auto e = entity_slot_.find(entity);
    if (c == client_index_.end() || e == entity_slot_.end()) {
        return {};
    }
    const ClientSlot& cs = *clients_[c->second];
    const auto& pair = cs.pairs[e->second];
    return pair.group == kNoGroup ? Aabb{} : cs.groups[pair.group].box;
}

std::size_t InterestManager::tbv_count(ClientId id) const {
    const auto it = client_index_.find(id);
    return it == client_index_.end() ? 0 : clients_[it->second]->live_groups;
}

} // namespace dsoc::visibility
