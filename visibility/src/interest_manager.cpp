#include "dsoc/visibility/interest_manager.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <deque>
#include <functional>
#include <stdexcept>
#include <string>

namespace dsoc::visibility {

namespace {

constexpr std::uint32_t kNoGroup = 0xffffffffu;
/// Slack for float noise when checking a move against the motion limits. [Units: world units]
constexpr float kTeleportTolerance = 0.05f;
/// Groups created this tick that a new TBV may join (bounds the merge scan).
constexpr std::size_t kMergeCandidates = 8;
/// A TBV may join a group that expires up to this many ticks before it does (and is
/// then cut short to the group's expiry). [Units: ticks]
constexpr std::uint64_t kMergeExpirySlack = 4;
/// Candidate TBV durations tried per hide (each half the previous).
constexpr int kMaxTbvAttempts = 3;
/// After every candidate TBV was visible, the entity is only box-tested for this many
/// ticks before TBVs are tried again (entities at the edge of visibility would
/// otherwise pay for failed TBV tests every tick). [Units: ticks]
constexpr std::uint64_t kTbvRetryTicks = 8;
/// No entity cluster. Clusters of fewer members are not worth a test of their own.
constexpr std::uint32_t kNoCluster = 0xffffffffu;
constexpr std::size_t kMinClusterMembers = 3;

/// A box the manager accepts: finite and not empty.
bool valid_box(const Aabb& b) {
    return std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) &&
           std::isfinite(b.max.x) && std::isfinite(b.max.y) && std::isfinite(b.max.z) &&
           !b.is_empty();
}

} // namespace

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

struct InterestManager::EntitySlot {
    EntityId id = 0;
    bool alive = false;
    EntityDesc desc;
    Aabb box;
    Aabb box_at_last_update;
    bool seen_by_update = false;
    std::uint64_t teleported_at = 0; ///< tick of the last detected jump (0: never)
    float speed_per_tick = 0.0f;     ///< horizontal, from the last two updates
    float down_velocity = -1.0f;     ///< current downward speed, < 0 when unknown
    MovementHistory history;
    PreparedBox prepared; ///< `box` prepared for the culler, once per tick for all clients
    /// With a prepared stage: candidate TBVs made at tick `candidates_tick` (durations
    /// d, d/2, d/4; 0 ends the list), prepared once and shared by every client that hides
    /// the entity before they expire. A TBV depends on the entity alone; only whether it
    /// is hidden depends on the client.
    std::array<PreparedBox, kMaxTbvAttempts> tbv_candidates;
    std::array<int, kMaxTbvAttempts> tbv_durations{};
    std::uint64_t candidates_tick = 0;
    bool has_candidates = false;
    /// TBVs the entity held across all clients when this tick began: the per-object
    /// cap reads this, not the live counter, so decisions do not depend on the order
    /// in which parallel update_client() calls run.
    std::int32_t tbvs_at_tick_start = 0;

    /// `prepared` (and the entity's cluster box) is current: the box was not set after
    /// begin_update().
    [[nodiscard]] bool prepared_is_current() const {
        return prepared.box.min == box.min && prepared.box.max == box.max;
    }
};

struct InterestManager::TbvGroup {
    Aabb box;
    /// With a prepared stage: the union of the members' TBV keys. The group is hidden
    /// while the cheap stage proves every member TBV hidden (see hide()).
    PreparedBox prepared;
    std::uint64_t expiry = 0; ///< last tick the group is valid
    std::uint32_t generation = 0;
    bool alive = false;
    std::vector<std::uint32_t> members; ///< entity slots
};

/// Entities whose box centres share a cell of DSOCConfig::entity_cluster_size.
struct InterestManager::EntityCluster {
    PreparedBox prepared;               ///< union of the members' boxes at begin_update()
    std::vector<std::uint32_t> members; ///< entity slots, increasing
};

struct InterestManager::ClientSlot {
    struct Pair {
        PairState state = PairState::unknown;
        std::uint32_t group = kNoGroup;
        /// The culler's hint for this box (test_prepared_hinted): e.g. its last blocker.
        std::uint32_t hint = 0;
        /// No TBV is tried before this tick (back-off after a rejected TBV).
        std::uint64_t next_tbv_tick = 0;
    };
    struct Expiry {
        std::uint64_t tick;
        std::uint32_t group;
        std::uint32_t generation;
        bool operator>(const Expiry& o) const { return tick > o.tick; }
    };

    ClientSlot(ClientId client_id, const ClientDesc& d, const LooseOctreeConfig& tree_config,
               std::unique_ptr<RegionVisibility> v)
        : id(client_id), desc(d), visibility(std::move(v)), tree(tree_config) {}

    ClientId id;
    ClientDesc desc;
    glm::vec3 eye{0.0f}; ///< at the last update
    glm::vec3 spectator_eye{0.0f};
    bool has_spectator_eye = false;
    std::unique_ptr<RegionVisibility> visibility; ///< built for buffer_region (TBVs)
    /// Built every tick for `region` alone, for the current boxes (exact_region_tests);
    /// made on first use.
    std::unique_ptr<RegionVisibility> exact;
    Aabb buffer_region;
    Aabb region;
    std::vector<Pair> pairs; // by entity slot
    LooseOctree tree;        // item id = group index
    std::vector<TbvGroup> groups;
    std::vector<std::uint32_t> free_groups;
    std::size_t live_groups = 0;
    std::priority_queue<Expiry, std::vector<Expiry>, std::greater<>> expiries;
    std::vector<std::uint32_t> new_groups;
    std::vector<std::uint32_t> scratch;
    PreparedBox candidate; // hide()'s TBV candidate, reused
    /// By cluster, this tick: 0 not proven hidden, 1 proven hidden, 2 members decided.
    std::vector<std::uint8_t> cluster_hidden;
    std::vector<std::uint32_t> cluster_members; // hide_cluster()'s scratch
    std::vector<EntityId> previous;             // replicated ids of the last update, increasing
    ClientDecisions decisions;
    ClientStats stats;
};

InterestManager::InterestManager(const DSOCConfig& config, const Aabb& world_bounds,
                                 RegionVisibilityFactory make_visibility, EyeRegionClipper clipper)
    : config_(config), world_bounds_(world_bounds), make_visibility_(std::move(make_visibility)),
      clipper_(std::move(clipper)), tick_seconds_(1.0f / static_cast<float>(config.tick_rate)) {
    if (const auto problems = validate(config_); !problems.empty()) {
        throw std::invalid_argument("DSOCConfig: " + problems.front());
    }
    if (make_visibility_) {
        preparer_ = make_visibility_();
        coarse_tbvs_ = preparer_ != nullptr && preparer_->has_prepared_stage();
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
        counts.emplace_back(0);
        for (auto& c : clients_) {
            c->pairs.resize(entities_.size());
        }
    }
    EntitySlot& e = entities_[slot];
    e = EntitySlot{};
    e.id = id;
    e.alive = true;
    e.desc = desc;
    e.box = box;
    e.box_at_last_update = box;
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
        if (c->pairs[slot].state == PairState::hidden_with_tbv) {
            release_group_member(*c, slot);
        }
        c->pairs[slot] = {};
    }
    entities_[slot].alive = false;
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
    for (std::size_t slot = 0; slot < c.pairs.size(); ++slot) {
        if (c.pairs[slot].state == PairState::hidden_with_tbv) {
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
    return clients_[c->second]->pairs[e->second].state;
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

// ---- the tick --------------------------------------------------------------------

void InterestManager::update(std::uint64_t tick) {
    begin_update(tick);
    for (std::size_t i = 0; i < clients_.size(); ++i) {
        update_client(i);
    }
    if (config_.validate_state) {
        require_valid_state("at tick " + std::to_string(tick));
    }
}

void InterestManager::require_valid_state(const std::string& when) const {
    const auto problems = validate_state();
    if (!problems.empty()) {
        throw std::logic_error("ValidateDSOCState " + when + ": " + problems.front() + " (and " +
                               std::to_string(problems.size() - 1) + " more)");
    }
}

void InterestManager::begin_update(std::uint64_t tick) {
    const std::uint64_t elapsed = tick > tick_ && tick_ != 0 ? tick - tick_ : 1;
    tick_ = tick;
    const float seconds = static_cast<float>(elapsed) * tick_seconds_;
    for (EntitySlot& e : entities_) {
        if (!e.alive) {
            continue;
        }
        const glm::vec3 from = e.box_at_last_update.center();
        const glm::vec3 to = e.box.center();
        if (e.seen_by_update &&
            !within_reach(from, to, e.desc.motion, seconds, kTeleportTolerance)) {
            e.teleported_at = tick;
            e.history.clear();
        }
        const glm::vec3 d = to - from;
        e.speed_per_tick = e.seen_by_update
                               ? std::sqrt(d.x * d.x + d.y * d.y) / static_cast<float>(elapsed)
                               : 0.0f;
        e.history.push(to);
        e.box_at_last_update = e.box;
        e.seen_by_update = true;
        e.tbvs_at_tick_start = tbv_counts_[static_cast<std::size_t>(&e - entities_.data())].load(
            std::memory_order_relaxed);
        if (preparer_) {
            preparer_->prepare(e.box, e.prepared);
        } else {
            e.prepared.box = e.box;
        }
        // Refresh the shared candidates when half the longest has run out (or it jumped).
        if (coarse_tbvs_ && tbvs_enabled_ &&
            (!e.has_candidates || e.teleported_at == tick ||
             tick >= e.candidates_tick + static_cast<std::uint64_t>(e.tbv_durations[0] / 2))) {
            e.has_candidates = true;
            e.candidates_tick = tick;
            int duration = tbv_duration(e);
            for (std::size_t k = 0; k < e.tbv_candidates.size(); ++k, duration /= 2) {
                e.tbv_durations[k] = duration;
                if (duration >= 1) {
                    PreparedBox& candidate = e.tbv_candidates[k];
                    preparer_->prepare(tbv_box(e, duration), candidate);
                }
            }
        }
    }
    build_clusters();
}

void InterestManager::build_clusters() {
    cluster_of_.assign(entities_.size(), kNoCluster);
    for (std::size_t k = 0; k < cluster_count_; ++k) {
        clusters_[k].members.clear();
    }
    cluster_count_ = 0;
    if (!clusters_enabled_) {
        return;
    }
    cluster_cells_.clear();
    const float inv = 1.0f / config_.entity_cluster_size;
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        const EntitySlot& e = entities_[slot];
        if (!e.alive) {
            continue;
        }
        const glm::vec3 cell = glm::floor(e.box.center() * inv);
        // 21 bits per axis: cells within +-2^20 of the origin (any float world).
        const auto key_of = [](float v) {
            return static_cast<std::uint64_t>(std::clamp(static_cast<std::int64_t>(v),
                                                         std::int64_t{-(1 << 20)},
                                                         std::int64_t{(1 << 20) - 1}) +
                                              (1 << 20)) &
                   0x1fffffu;
        };
        const std::uint64_t key = key_of(cell.x) | key_of(cell.y) << 21 | key_of(cell.z) << 42;
        const auto [it, added] =
            cluster_cells_.try_emplace(key, static_cast<std::uint32_t>(cluster_count_));
        if (added) {
            if (clusters_.size() == cluster_count_) {
                clusters_.emplace_back();
            }
            ++cluster_count_;
        }
        clusters_[it->second].members.push_back(slot);
    }
    for (std::uint32_t k = 0; k < cluster_count_; ++k) {
        EntityCluster& cluster = clusters_[k];
        if (cluster.members.size() < kMinClusterMembers) {
            continue;
        }
        Aabb box;
        for (const std::uint32_t slot : cluster.members) {
            box.extend(entities_[slot].box);
            cluster_of_[slot] = k;
        }
        if (preparer_) {
            preparer_->prepare(box, cluster.prepared);
        } else {
            cluster.prepared.box = box;
            cluster.prepared.prepared = false;
        }
    }
}

Aabb InterestManager::eye_region_for(const ClientSlot& c, glm::vec3& eye) const {
    if (c.desc.viewer != kNoEntity) {
        const auto it = entity_slot_.find(c.desc.viewer);
        if (it == entity_slot_.end()) {
            return {};
        }
        eye = entities_[it->second].box.center() + c.desc.eye_offset;
    } else if (c.has_spectator_eye) {
        eye = c.spectator_eye;
    } else {
        return {};
    }
    float down_velocity = -1.0f;
    if (c.desc.viewer != kNoEntity) {
        down_velocity = entities_[entity_slot_.at(c.desc.viewer)].down_velocity;
    }
    return reachable_eye_region(c.desc, eye, down_velocity);
}

Aabb InterestManager::reachable_eye_region(const ClientDesc& desc, glm::vec3 eye,
                                           float down_velocity) const {
    const float seconds = static_cast<float>(desc.lookahead_ticks) * tick_seconds_;
    const Aabb region =
        clip(reachable_box(Aabb{eye, eye}, desc.eye_motion, seconds, 1.0f, down_velocity));
    return clipper_ ? clipper_(eye, region, EyeReach{&desc.eye_motion, seconds, down_velocity})
                    : region;
}

void InterestManager::update_client(std::size_t index, UpdateEffort effort) {
    ClientSlot& c = *clients_[index];
    const bool cheapest = effort == UpdateEffort::cheapest;
    c.stats.cheapest_updates += cheapest ? 1 : 0;
    c.region = eye_region_for(c, c.eye);
    if (c.region.is_empty()) { // no eye: nothing may be known
        for (auto& pair : c.pairs) {
            if (pair.state == PairState::visible) {
                pair.state = PairState::unknown;
            }
        }
        decide(c);
        return;
    }

    // 1. The culler: reuse it while the reachable region stays inside its region. Only
    //    TBVs need a culler for a larger region than this tick's; without them (and with
    //    exact_region_tests) it is built for this tick's region alone.
    const bool reuse = config_.reuse_buffers && (tbvs_enabled_ || !config_.exact_region_tests);
    bool rebuilt = false;
    if (!reuse || c.buffer_region.is_empty() || !c.buffer_region.contains(c.region)) {
        c.buffer_region = c.region;
        if (reuse && config_.region_reuse_margin > 0.0f) {
            const Aabb grown = clip(c.region.expanded(config_.region_reuse_margin));
            c.buffer_region = clipper_ ? clipper_(c.eye, grown, EyeReach{}) : grown;
        }
        c.visibility->build(c.buffer_region);
        ++c.stats.buffer_builds;
        rebuilt = true;
    }

    // The current boxes need only be hidden from this tick's region: with a reused
    // (larger) buffer region, test them against a culler built for exactly it.
    // (The cheapest effort tests against the buffer's region, which holds this one.)
    RegionVisibility* now = c.visibility.get();
    if (config_.exact_region_tests && !cheapest &&
        (c.buffer_region.min != c.region.min || c.buffer_region.max != c.region.max)) {
        if (!c.exact) {
            c.exact = make_visibility_();
        }
        c.exact->build(c.region);
        now = c.exact.get();
    }

    // 2. Expired TBV groups: their entities must be tested again.
    while (!c.expiries.empty() && c.expiries.top().tick < tick_) {
        c.stats.tbvs_expired += expire_earliest_group(c);
    }

    // 3. Teleports void the TBVs of the entity that jumped. A fuzzy TBV is a prediction,
    //    not a bound: one the entity has left is void too (caught the first tick it is
    //    outside, so its box is tested before it could be seen).
    const bool fuzzy = config_.strategy == TbvStrategy::fuzzy;
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        const EntitySlot& e = entities_[slot];
        auto& pair = c.pairs[slot];
        if (!e.alive || pair.state != PairState::hidden_with_tbv) {
            continue;
        }
        const bool jumped = e.teleported_at == tick_;
        const bool escaped = !jumped && fuzzy && !c.groups[pair.group].box.contains(e.box);
        if (jumped || escaped) {
            release_group_member(c, slot);
            pair.state = PairState::hidden_expired;
            ++(jumped ? c.stats.teleports : c.stats.fuzzy_escapes);
        }
    }

    // 4. A new culler region: every TBV must prove itself hidden again. A visible TBV
    //    triggers a real test of its entities' current boxes (below).
    if (rebuilt && c.live_groups > 0) {
        c.scratch.clear();
        if (coarse_tbvs_) {
            // Each group carries its keys: re-proving it costs a few bit tests, cheaper
            // than any octree traversal.
            for (std::uint32_t g = 0; g < c.groups.size(); ++g) {
                if (c.groups[g].alive && c.visibility->test_prepared_coarse(c.groups[g].prepared) !=
                                             Visibility::occluded) {
                    c.scratch.push_back(g);
                }
            }
        } else {
            c.tree.traverse_front_to_back(c.region.center(), *c.visibility,
                                          [&](ItemId group) { c.scratch.push_back(group); });
        }
        for (const std::uint32_t group : c.scratch) {
            ++c.stats.tbv_hits;
            for (const std::uint32_t slot : c.groups[group].members) {
                c.pairs[slot].state = PairState::hidden_expired;
            }
            free_group(c, group);
        }
    }

    // 5. Every entity without a hidden TBV: test its current box.
    c.new_groups.clear();
    const auto viewer =
        c.desc.viewer != kNoEntity ? entity_slot_.find(c.desc.viewer) : entity_slot_.end();
    const std::uint32_t viewer_slot = viewer != entity_slot_.end() ? viewer->second : kNoGroup;
    // Temporal coherence: an entity visible last tick most likely still is; give it
    // the full (slower) test only every full_test_interval ticks, staggered.
    const auto quick_test = [&](std::uint32_t slot) {
        return c.pairs[slot].state == PairState::visible &&
               (tick_ + slot) % static_cast<std::uint64_t>(config_.full_test_interval) != 0;
    };
    // e.prepared (and its cluster's box) is current unless the box was set after
    // begin_update().
    const auto fresh_box = [&](std::uint32_t slot) {
        return entities_[slot].prepared_is_current();
    };

    // 5a. Clusters with at least two members due a full test: one test of the union
    //     of their boxes may hide them all.
    c.cluster_hidden.assign(cluster_count_, 0);
    for (std::uint32_t k = 0; k < (cheapest ? 0 : cluster_count_); ++k) {
        const EntityCluster& cluster = clusters_[k];
        if (cluster.members.size() < kMinClusterMembers) {
            continue;
        }
        int due = 0;
        for (const std::uint32_t slot : cluster.members) {
            const bool decided = c.pairs[slot].state == PairState::hidden_with_tbv ||
                                 slot == viewer_slot || !fresh_box(slot);
            due += decided || quick_test(slot) ? 0 : 1;
        }
        if (due < 2) {
            continue;
        }
        ++c.stats.cluster_tests;
        if (now->test_prepared(cluster.prepared) == Visibility::occluded) {
            c.cluster_hidden[k] = 1;
            ++c.stats.cluster_hits;
        }
    }

    // 5b. Each entity.
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        const EntitySlot& e = entities_[slot];
        auto& pair = c.pairs[slot];
        if (!e.alive || pair.state == PairState::hidden_with_tbv) {
            continue;
        }
        if (slot == viewer_slot) {
            pair.state = PairState::visible;
            continue;
        }
        const bool fresh = fresh_box(slot);
        const std::uint32_t cluster = cluster_of_[slot];
        if (fresh && cluster != kNoCluster && c.cluster_hidden[cluster] != 0) {
            // Hidden with its cluster (whose box holds this one's current box).
            if (c.cluster_hidden[cluster] == 1) {
                c.cluster_hidden[cluster] = 2;
                hide_cluster(c, cluster, viewer_slot);
            }
            if (pair.state != PairState::hidden_with_tbv) {
                pair.state = PairState::hidden_expired; // hide_cluster() made no TBV
            }
            continue;
        }
        ++c.stats.box_tests;
        if (cheapest) {
            // A box set after begin_update() has no preparation: visible, never guessed.
            const bool hidden =
                fresh && now->test_prepared_coarse(e.prepared) == Visibility::occluded;
            pair.state = hidden ? PairState::hidden_expired : PairState::visible;
            continue;
        }
        const bool quick = quick_test(slot);
        const Visibility v =
            quick ? (fresh ? now->test_prepared_quick(e.prepared) : now->test_box_quick(e.box))
            : !config_.blocker_hints
                ? (fresh ? now->test_prepared(e.prepared) : now->test_box(e.box))
            : fresh ? now->test_prepared_hinted(e.prepared, pair.hint)
                    : now->test_box_hinted(e.box, pair.hint);
        if (v == Visibility::visible) {
            pair.state = PairState::visible;
        } else {
            hide(c, slot);
        }
    }
    decide(c);
}

Aabb InterestManager::clip(const Aabb& box) const {
    if (world_bounds_.is_empty()) {
        return box;
    }
    Aabb out{glm::max(box.min, world_bounds_.min), glm::min(box.max, world_bounds_.max)};
    return out.is_empty() ? box : out;
}

int InterestManager::tbv_duration(const EntitySlot& e) const {
    switch (config_.strategy) {
    case TbvStrategy::explicit_duration:
        return config_.default_tbv_duration;
    case TbvStrategy::adaptive:
    case TbvStrategy::fuzzy:
        return adaptive_duration(e.speed_per_tick, e.desc.motion.horizontal_speed * tick_seconds_,
                                 config_);
    }
    return config_.default_tbv_duration;
}

Aabb InterestManager::tbv_box(const EntitySlot& e, int duration) const {
    if (config_.strategy == TbvStrategy::fuzzy) {
        return clip(fuzzy_box(e.box, e.history, duration, tick_seconds_, config_.fuzzy_confidence,
                              e.desc.motion));
    }
    return clip(reachable_box(e.box, e.desc.motion, static_cast<float>(duration) * tick_seconds_,
                              config_.tbv_expansion_factor, e.down_velocity));
}

void InterestManager::hide(ClientSlot& c, std::uint32_t slot) {
    auto& pair = c.pairs[slot];
    if (!tbvs_enabled_ || tick_ < pair.next_tbv_tick ||
        entities_[slot].tbvs_at_tick_start >= config_.max_tbvs_per_object) {
        pair.state = PairState::hidden_expired;
        return;
    }
    const EntitySlot& e = entities_[slot];
    // The longest TBV that is itself hidden: halve the duration until it is. With a
    // prepared stage (the map's PVS) a TBV is proven by that stage alone, so that
    // re-proving it after each rebuild costs a few bit tests (step 4 of update_client).
    const PreparedBox* found = nullptr;
    int duration = 0;
    std::uint64_t expiry = 0;
    if (coarse_tbvs_) {
        for (std::size_t k = 0; k < e.tbv_candidates.size() && e.tbv_durations[k] >= 1; ++k) {
            const std::uint64_t last =
                e.candidates_tick + static_cast<std::uint64_t>(e.tbv_durations[k]);
            if (!e.has_candidates || last <= tick_) {
                break; // this and the shorter ones have run out
            }
            ++c.stats.tbv_tests;
            if (c.visibility->test_prepared_coarse(e.tbv_candidates[k]) == Visibility::occluded) {
                found = &e.tbv_candidates[k];
                expiry = last;
                break;
            }
        }
    } else {
        duration = tbv_duration(e);
        for (int attempt = 0; attempt < kMaxTbvAttempts && duration >= 1;
             ++attempt, duration /= 2) {
            c.candidate.box = tbv_box(e, duration);
            c.candidate.prepared = false;
            ++c.stats.tbv_tests;
            if (c.visibility->test_box(c.candidate.box) == Visibility::occluded) {
                found = &c.candidate;
                expiry = tick_ + static_cast<std::uint64_t>(duration);
                break;
            }
        }
    }
    if (found == nullptr) {
        pair.state = PairState::hidden_expired;
        pair.next_tbv_tick = tick_ + kTbvRetryTicks;
        ++c.stats.tbvs_rejected;
        return;
    }
    const PreparedBox& candidate = *found;
    const Aabb box = candidate.box;
    if (expiry <= tick_) {
        pair.state = PairState::hidden_expired;
        pair.next_tbv_tick = tick_ + kTbvRetryTicks;
        ++c.stats.tbvs_rejected;
        return;
    }
    // Group with a TBV made this tick nearby that expires no later than this one (the
    // group keeps its expiry, so every member's TBV still holds it until then), when
    // the grown group is still hidden.
    std::uint32_t group = kNoGroup;
    if (config_.tbv_merge_distance > 0.0f) {
        const float r2 = config_.tbv_merge_distance * config_.tbv_merge_distance;
        const std::size_t first =
            c.new_groups.size() > kMergeCandidates ? c.new_groups.size() - kMergeCandidates : 0;
        for (std::size_t i = c.new_groups.size(); i-- > first;) {
            TbvGroup& g = c.groups[c.new_groups[i]];
            const glm::vec3 d = g.box.center() - box.center();
            if (g.expiry > expiry || g.expiry + kMergeExpirySlack < expiry || glm::dot(d, d) > r2 ||
                (coarse_tbvs_ && (!candidate.prepared || !g.prepared.prepared))) {
                continue;
            }
            Aabb merged = g.box;
            merged.extend(box);
            if (coarse_tbvs_) {
                // The group is hidden exactly while every member TBV is: its keys are
                // the union of theirs, no test needed.
                preparer_->merge_prepared(g.prepared, candidate);
                g.prepared.box = merged;
            } else {
                ++c.stats.tbv_tests;
                if (c.visibility->test_box(merged) != Visibility::occluded) {
                    continue;
                }
                g.prepared.box = merged;
            }
            group = c.new_groups[i];
            g.box = merged;
            c.tree.move(group, merged);
            ++c.stats.tbvs_merged;
            break;
        }
    }
    if (group == kNoGroup) {
        group = new_group(c, candidate, expiry);
    }
    join_group(c, group, slot);
}

std::uint32_t InterestManager::new_group(ClientSlot& c, const PreparedBox& prepared,
                                         std::uint64_t expiry) {
    const std::uint32_t group = allocate_group(c);
    TbvGroup& g = c.groups[group];
    g.box = prepared.box;
    g.prepared = prepared;
    g.expiry = expiry;
    c.tree.insert(group, g.box);
    c.expiries.push({expiry, group, g.generation});
    c.new_groups.push_back(group);
    return group;
}

void InterestManager::join_group(ClientSlot& c, std::uint32_t group, std::uint32_t slot) {
    c.groups[group].members.push_back(slot);
    auto& pair = c.pairs[slot];
    pair.state = PairState::hidden_with_tbv;
    pair.group = group;
    tbv_counts_[slot].fetch_add(1, std::memory_order_relaxed);
    ++c.stats.tbvs_created;
}

void InterestManager::hide_cluster(ClientSlot& c, std::uint32_t cluster,
                                   std::uint32_t viewer_slot) {
    // Members still undecided this tick (the caller visits them after this call).
    auto& members = c.cluster_members;
    members.clear();
    for (const std::uint32_t slot : clusters_[cluster].members) {
        const EntitySlot& e = entities_[slot];
        if (e.alive && slot != viewer_slot && c.pairs[slot].state != PairState::hidden_with_tbv &&
            e.prepared_is_current()) {
            members.push_back(slot);
        }
    }
    // With a prepared stage each member's own TBV costs a few bit tests: no group.
    if (coarse_tbvs_ || !tbvs_enabled_) {
        for (const std::uint32_t slot : members) {
            hide(c, slot);
        }
        return;
    }
    // Members allowed a TBV now (the same rules as hide()); the others only hide.
    std::size_t eligible = 0;
    int duration = std::numeric_limits<int>::max();
    for (const std::uint32_t slot : members) {
        if (tick_ < c.pairs[slot].next_tbv_tick ||
            entities_[slot].tbvs_at_tick_start >= config_.max_tbvs_per_object) {
            c.pairs[slot].state = PairState::hidden_expired;
            continue;
        }
        members[eligible++] = slot;
        duration = std::min(duration, tbv_duration(entities_[slot]));
    }
    members.resize(eligible);
    // One TBV for all: the union of every member's TBV for the shortest duration,
    // halved until hidden.
    for (int attempt = 0; attempt < kMaxTbvAttempts && duration >= 1 && !members.empty();
         ++attempt, duration /= 2) {
        Aabb box;
        for (const std::uint32_t slot : members) {
            box.extend(tbv_box(entities_[slot], duration));
        }
        ++c.stats.tbv_tests;
        if (c.visibility->test_box(box) == Visibility::occluded) {
            PreparedBox prepared;
            prepared.box = box;
            const std::uint32_t group =
                new_group(c, prepared, tick_ + static_cast<std::uint64_t>(duration));
            for (const std::uint32_t slot : members) {
                join_group(c, group, slot);
            }
            return;
        }
    }
    for (const std::uint32_t slot : members) {
        hide(c, slot); // each on its own, as without clusters
    }
}

std::size_t InterestManager::expire_earliest_group(ClientSlot& c) {
    const auto top = c.expiries.top();
    c.expiries.pop();
    TbvGroup& g = c.groups[top.group];
    if (!g.alive || g.generation != top.generation) {
        return 0; // stale heap entry: the group was freed or reused since
    }
    for (const std::uint32_t slot : g.members) {
        c.pairs[slot].state = PairState::hidden_expired;
    }
    const std::size_t members = g.members.size();
    free_group(c, top.group);
    return members;
}

std::uint32_t InterestManager::allocate_group(ClientSlot& c) {
    if (c.free_groups.empty() &&
        c.groups.size() >= static_cast<std::size_t>(config_.max_tbvs_per_client)) {
        // Memory pressure: evict the group that expires first; its entities are
        // re-tested every tick from now on, never forgotten.
        while (!c.expiries.empty()) {
            if (expire_earliest_group(c) > 0) {
                ++c.stats.evictions;
                break;
            }
        }
    }
    std::uint32_t group;
    if (!c.free_groups.empty()) {
        group = c.free_groups.back();
        c.free_groups.pop_back();
    } else {
        group = static_cast<std::uint32_t>(c.groups.size());
        c.groups.emplace_back();
    }
    TbvGroup& g = c.groups[group];
    g.alive = true;
    ++g.generation;
    g.members.clear();
    ++c.live_groups;
    return group;
}

void InterestManager::free_group(ClientSlot& c, std::uint32_t group) {
    TbvGroup& g = c.groups[group];
    if (!g.alive) {
        return;
    }
    auto& counts = tbv_counts_;
    for (const std::uint32_t slot : g.members) {
        counts[slot].fetch_sub(1, std::memory_order_relaxed);
        if (c.pairs[slot].group == group) {
            c.pairs[slot].group = kNoGroup;
        }
    }
    g.members.clear();
    g.alive = false;
    c.tree.remove(group);
    c.free_groups.push_back(group);
    --c.live_groups;
}

void InterestManager::release_group_member(ClientSlot& c, std::uint32_t slot) {
    auto& pair = c.pairs[slot];
    if (pair.group == kNoGroup) {
        return;
    }
    TbvGroup& g = c.groups[pair.group];
    const auto it = std::find(g.members.begin(), g.members.end(), slot);
    if (it != g.members.end()) {
        g.members.erase(it);
        tbv_counts_[slot].fetch_sub(1, std::memory_order_relaxed);
    }
    const std::uint32_t group = pair.group;
    pair.group = kNoGroup;
    if (g.members.empty()) {
        free_group(c, group);
    }
}

void InterestManager::decide(ClientSlot& c) {
    ClientDecisions& d = c.decisions;
    d.enter.clear();
    d.leave.clear();
    d.replicated.clear();
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        const EntitySlot& e = entities_[slot];
        if (!e.alive || c.pairs[slot].state != PairState::visible) {
            continue;
        }
        Replicated r;
        r.id = e.id;
        // Conservative distance: nearest points of the eye region and the box.
        const glm::vec3 gap =
            glm::max(glm::vec3(0.0f), glm::max(c.region.min - e.box.max, e.box.min - c.region.max));
        const float distance = std::sqrt(glm::dot(gap, gap));
        if (distance < config_.lod_near_distance) {
            r.update_interval = 1;
            r.position_precision = 0.125f;
        } else if (distance < config_.lod_far_distance) {
            r.update_interval = 2;
            r.position_precision = 0.5f;
        } else {
            r.update_interval = 4;
            r.position_precision = 1.0f;
        }
        d.replicated.push_back(r);
    }
    std::sort(d.replicated.begin(), d.replicated.end(),
              [](const Replicated& a, const Replicated& b) { return a.id < b.id; });
    // Diff against the previous set (both increasing).
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < c.previous.size() || j < d.replicated.size()) {
        if (j == d.replicated.size() ||
            (i < c.previous.size() && c.previous[i] < d.replicated[j].id)) {
            d.leave.push_back(c.previous[i++]);
        } else if (i == c.previous.size() || d.replicated[j].id < c.previous[i]) {
            d.enter.push_back(d.replicated[j++].id);
        } else {
            ++i;
            ++j;
        }
    }
    c.previous.clear();
    for (const auto& r : d.replicated) {
        c.previous.push_back(r.id);
    }
}

std::vector<std::string> InterestManager::validate_state() const {
    std::vector<std::string> problems;
    const auto say = [&](ClientId c, EntityId e, const std::string& what) {
        problems.push_back("client " + std::to_string(c) + ", entity " + std::to_string(e) + ": " +
                           what);
    };
    for (const auto& cp : clients_) {
        const ClientSlot& c = *cp;
        std::size_t live = 0;
        for (std::uint32_t g = 0; g < c.groups.size(); ++g) {
            const TbvGroup& group = c.groups[g];
            if (!group.alive) {
                continue;
            }
            ++live;
            if (!c.tree.contains(g)) {
                problems.push_back("client " + std::to_string(c.id) + ": group " +
                                   std::to_string(g) + " missing from the octree");
            }
            if (group.members.empty()) {
                problems.push_back("client " + std::to_string(c.id) + ": empty live group");
            }
            for (const std::uint32_t slot : group.members) {
                if (c.pairs[slot].group != g || c.pairs[slot].state != PairState::hidden_with_tbv) {
                    say(c.id, entities_[slot].id, "member of a group it does not point to");
                }
            }
        }
        if (live != c.live_groups) {
            problems.push_back("client " + std::to_string(c.id) + ": live group count mismatch");
        }
        for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
            const EntitySlot& e = entities_[slot];
            const auto& pair = c.pairs[slot];
            if (!e.alive) {
                if (pair.state != PairState::unknown || pair.group != kNoGroup) {
                    problems.push_back("client " + std::to_string(c.id) +
                                       ": state kept for a removed entity");
                }
                continue;
            }
            if (pair.state == PairState::visible && pair.group != kNoGroup) {
                say(c.id, e.id, "visible but holds a TBV");
            }
            if (pair.state != PairState::hidden_with_tbv) {
                continue;
            }
            if (pair.group == kNoGroup || !c.groups[pair.group].alive) {
                say(c.id, e.id, "hidden_with_tbv without a live TBV");
                continue;
            }
            const TbvGroup& g = c.groups[pair.group];
            if (g.expiry < tick_) {
                say(c.id, e.id, "TBV expired at tick " + std::to_string(g.expiry));
            }
            if (!g.box.contains(e.box) && e.teleported_at != tick_) {
                say(c.id, e.id, "box left its TBV (moved faster than its motion limits?)");
            }
        }
    }
    return problems;
}

} // namespace dsoc::visibility
