// InterestManager: the tick. begin_update() does the serial work shared by all
// clients; update_client() runs one client's steps in order, each a named function;
// and the reachable eye region every step works from.

#include "interest_manager_state.hpp"

#include <atomic>
#include <cmath>
#include <string>

namespace dsoc::visibility {

using detail::kMinClusterMembers;
using detail::kNoCluster;
using detail::kNoGroup;
using detail::kTeleportTolerance;

namespace {

/// The culler's tests of one entity's current box.
enum class BoxTest : std::uint8_t {
    quick,  ///< visible last tick and not due a full test (temporal coherence)
    full,   ///< the full test
    hinted, ///< the full test, with the pair's hint (DSOCConfig::blocker_hints)
};

BoxTest box_test_for(bool quick, bool blocker_hints) {
    if (quick) {
        return BoxTest::quick;
    }
    return blocker_hints ? BoxTest::hinted : BoxTest::full;
}

/// Runs test `kind` on an entity's current box: on its preparation of this tick when
/// `use_preparation` (which then holds `box`), else on the box itself (a box set after
/// begin_update() has none).
Visibility test_current_box(const RegionVisibility& culler, BoxTest kind,
                            const PreparedBox& prepared, const Aabb& box, bool use_preparation,
                            std::uint32_t& hint) {
    switch (kind) {
    case BoxTest::quick:
        return use_preparation ? culler.test_prepared_quick(prepared) : culler.test_box_quick(box);
    case BoxTest::full:
        return use_preparation ? culler.test_prepared(prepared) : culler.test_box(box);
    case BoxTest::hinted:
        return use_preparation ? culler.test_prepared_hinted(prepared, hint)
                               : culler.test_box_hinted(box, hint);
    }
    return culler.test_box(box);
}

} // namespace

void InterestManager::update(std::uint64_t tick) {
    begin_update(tick);
    for (std::size_t i = 0; i < clients_.size(); ++i) {
        update_client(i);
    }
    if (config_.validate_state) {
        require_valid_state("at tick " + std::to_string(tick));
    }
}

// ---- begin_update(): serial, shared by all clients ---------------------------------

void InterestManager::begin_update(std::uint64_t tick) {
    const std::uint64_t elapsed = tick > tick_ && tick_ != 0 ? tick - tick_ : 1;
    tick_ = tick;
    const float seconds = static_cast<float>(elapsed) * tick_seconds_;
    for (EntitySlot& e : entities_) {
        if (!e.alive) {
            continue;
        }
        note_movement(e, elapsed, seconds);
        e.tbvs_at_tick_start = tbv_counts_[static_cast<std::size_t>(&e - entities_.data())].load(
            std::memory_order_relaxed);
        prepare_box(e);
        view_fresh_[static_cast<std::size_t>(&e - entities_.data())] =
            e.prepared_is_current() ? 1 : 0;
        refresh_tbv_candidates(e);
    }
    // Whose full test is due, for every client: stepped with the slot (a division per
    // entity and client costs more than the test of the answer).
    full_test_due_.resize(entities_.size());
    const auto interval = static_cast<std::uint32_t>(config_.full_test_interval);
    for (std::uint32_t slot = 0, phase = full_test_phase(0); slot < entities_.size();
         ++slot, phase = phase + 1 == interval ? 0 : phase + 1) {
        full_test_due_[slot] = phase == 0 ? 1 : 0;
    }
    packed_boxes_.clear();
    if (!tbvs_enabled_ && !clusters_enabled_) { // test_entities_in_bulk() may run
        for (const EntitySlot& e : entities_) {
            packed_boxes_.add(e.alive ? &e.prepared : nullptr);
        }
    }
    build_clusters();
}

void InterestManager::note_movement(EntitySlot& e, std::uint64_t elapsed, float seconds) {
    const glm::vec3 from = e.box_at_last_update.center();
    const glm::vec3 to = e.box.center();
    if (e.seen_by_update && !within_reach(from, to, e.desc.motion, seconds, kTeleportTolerance)) {
        e.teleported_at = tick_;
        e.history.clear();
    }
    const glm::vec3 d = to - from;
    e.speed_per_tick =
        e.seen_by_update ? std::sqrt(d.x * d.x + d.y * d.y) / static_cast<float>(elapsed) : 0.0f;
    e.history.push(to);
    e.box_at_last_update = e.box;
    e.seen_by_update = true;
}

void InterestManager::prepare_box(EntitySlot& e) {
    if (preparer_) {
        preparer_->prepare(e.box, e.prepared);
    } else {
        e.prepared.box = e.box;
    }
}

void InterestManager::refresh_tbv_candidates(EntitySlot& e) {
    // Refresh the shared candidates when half the longest has run out (or it jumped).
    const bool due =
        !e.has_candidates || e.teleported_at == tick_ ||
        tick_ >= e.candidates_tick + static_cast<std::uint64_t>(e.tbv_durations[0] / 2);
    if (!prepared_stage_ || !tbvs_enabled_ || !due) {
        return;
    }
    e.has_candidates = true;
    e.candidates_tick = tick_;
    int duration = tbv_duration(e);
    for (std::size_t k = 0; k < e.tbv_candidates.size(); ++k, duration /= 2) {
        e.tbv_durations[k] = duration;
        if (duration >= 1) {
            PreparedBox& candidate = e.tbv_candidates[k];
            preparer_->prepare(tbv_box(e, duration), candidate);
        }
    }
}

// ---- eye regions ---------------------------------------------------------------------

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

Aabb InterestManager::clip(const Aabb& box) const {
    if (world_bounds_.is_empty()) {
        return box;
    }
    Aabb out{glm::max(box.min, world_bounds_.min), glm::min(box.max, world_bounds_.max)};
    return out.is_empty() ? box : out;
}

// ---- update_client(): one client, its steps in order -----------------------------------

void InterestManager::update_client(std::size_t index, UpdateEffort effort) {
    ClientSlot& c = *clients_[index];
    c.stats.cheapest_updates += effort == UpdateEffort::cheapest ? 1 : 0;
    // The cheapest effort is the prepared stage alone. Without one nothing is cheaper
    // than the full path (clusters, hints, quick tests), which then runs.
    const bool cheapest = effort == UpdateEffort::cheapest && prepared_stage_;
    c.region = eye_region_for(c, c.eye);
    if (c.region.is_empty()) {
        forget_visible(c);
        decide(c);
        return;
    }
    // Steps 1 to 6, in this order (each declared with what it does in the header).
    const bool rebuilt = refresh_culler(c);
    const RegionVisibility& now = current_box_culler(c, cheapest);
    expire_tbvs(c);
    void_broken_tbvs(c);
    if (rebuilt) {
        reprove_tbvs(c);
    }
    c.new_groups.clear(); // groups made from here on may take more TBVs this tick (hide())
    const std::uint32_t viewer = viewer_slot_of(c);
    test_clusters(c, now, viewer, cheapest);
    test_entities(c, now, viewer, cheapest);
    decide(c);
}

void InterestManager::forget_visible(ClientSlot& c) {
    // No eye: nothing may be known.
    for (PairState& state : c.states) {
        if (state == PairState::visible) {
            state = PairState::unknown;
        }
    }
}

bool InterestManager::refresh_culler(ClientSlot& c) {
    // 1. The culler: reuse it while the reachable region stays inside its region. Only
    //    TBVs need a culler for a larger region than this tick's; without them (and with
    //    exact_region_tests) it is built for this tick's region alone.
    const bool reuse = config_.reuse_buffers && (tbvs_enabled_ || !config_.exact_region_tests);
    if (reuse && !c.buffer_region.is_empty() && c.buffer_region.contains(c.region)) {
        return false;
    }
    c.buffer_region = c.region;
    if (reuse && config_.region_reuse_margin > 0.0f) {
        const Aabb grown = clip(c.region.expanded(config_.region_reuse_margin));
        c.buffer_region = clipper_ ? clipper_(c.eye, grown, EyeReach{}) : grown;
    }
    c.visibility->build(c.buffer_region);
    ++c.stats.buffer_builds;
    return true;
}

const RegionVisibility& InterestManager::current_box_culler(ClientSlot& c, bool cheapest) {
    // The current boxes need only be hidden from this tick's region: with a reused
    // (larger) buffer region, test them against a culler built for exactly it.
    // (The cheapest effort tests against the buffer's region, which holds this one.)
    if (config_.exact_region_tests && !cheapest &&
        (c.buffer_region.min != c.region.min || c.buffer_region.max != c.region.max)) {
        if (!c.exact) {
            c.exact = make_visibility_();
        }
        c.exact->build(c.region);
        return *c.exact;
    }
    return *c.visibility;
}

void InterestManager::expire_tbvs(ClientSlot& c) {
    // 2. Expired TBV groups: their entities must be tested again.
    while (!c.expiries.empty() && c.expiries.top().tick < tick_) {
        c.stats.tbvs_expired += expire_earliest_group(c);
    }
}

void InterestManager::void_broken_tbvs(ClientSlot& c) {
    // 3. Teleports void the TBVs of the entity that jumped. A fuzzy TBV is a prediction,
    //    not a bound: one the entity has left is void too (caught the first tick it is
    //    outside, so its box is tested before it could be seen).
    if (c.live_groups == 0) {
        return; // no pair is hidden with a TBV
    }
    const bool fuzzy = config_.strategy == TbvStrategy::fuzzy;
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        const EntitySlot& e = entities_[slot];
        if (!e.alive || c.states[slot] != PairState::hidden_with_tbv) {
            continue;
        }
        const bool jumped = e.teleported_at == tick_;
        const bool escaped = !jumped && fuzzy && !c.groups[c.pairs[slot].group].box.contains(e.box);
        if (jumped || escaped) {
            release_group_member(c, slot);
            c.states[slot] = PairState::hidden_expired;
            ++(jumped ? c.stats.teleports : c.stats.fuzzy_escapes);
        }
    }
}

void InterestManager::reprove_tbvs(ClientSlot& c) {
    // 4. A new culler region: every TBV must prove itself hidden again. A visible TBV
    //    triggers a real test of its entities' current boxes (step 5).
    if (c.live_groups == 0) {
        return;
    }
    c.scratch.clear();
    if (prepared_stage_) {
        // Each group carries its keys: re-proving it costs a few bit tests, cheaper
        // than any octree traversal.
        for (std::uint32_t g = 0; g < c.groups.size(); ++g) {
            if (c.groups[g].alive &&
                c.visibility->test_prepared_coarse(c.groups[g].prepared) != Visibility::occluded) {
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
            c.states[slot] = PairState::hidden_expired;
        }
        free_group(c, group);
    }
}

std::uint32_t InterestManager::viewer_slot_of(const ClientSlot& c) const {
    const auto viewer =
        c.desc.viewer != kNoEntity ? entity_slot_.find(c.desc.viewer) : entity_slot_.end();
    return viewer != entity_slot_.end() ? viewer->second : kNoGroup;
}

bool InterestManager::takes_quick_test(const ClientSlot& c, std::uint32_t slot) const {
    // Temporal coherence: an entity visible last tick most likely still is; give it
    // the full (slower) test only every full_test_interval ticks, staggered.
    return c.states[slot] == PairState::visible && !full_test_due(slot);
}

bool InterestManager::full_test_due(std::uint32_t slot) const {
    // A slot added since begin_update() is past the column.
    return slot < full_test_due_.size() ? full_test_due_[slot] != 0 : full_test_phase(slot) == 0;
}

std::uint32_t InterestManager::full_test_phase(std::uint32_t slot) const {
    const auto interval = static_cast<std::uint64_t>(config_.full_test_interval);
    return static_cast<std::uint32_t>((tick_ + slot) % interval);
}

void InterestManager::test_entities_in_bulk(ClientSlot& c, const RegionVisibility& now,
                                            std::uint32_t viewer, bool cheapest) {
    // What test_entities() does when no pair holds a TBV, no entity is in a cluster,
    // hide() only marks the pair, and every kind of test is the coarse one: the boxes
    // prepared this tick are answered first, all together, then the pairs are set.
    // The answers of boxes changed or added since begin_update() are not read below.
    const std::size_t n = entities_.size();
    c.bulk_hidden.assign(n, 0);
    now.coarse_hidden_all(packed_boxes_,
                          std::span<std::uint8_t>(c.bulk_hidden).first(packed_boxes_.size()));
    for (std::uint32_t slot = 0; slot < n; ++slot) {
        const EntityView& view = views_[slot];
        if (view_alive_[slot] == 0) {
            continue;
        }
        PairState& state = c.states[slot];
        if (slot == viewer) {
            state = PairState::visible;
            continue;
        }
        ++c.stats.box_tests;
        // A box set after begin_update() has no preparation: tested as it is, or
        // visible for the cheapest effort (never guessed).
        const bool hidden = view_fresh_[slot] != 0
                                ? c.bulk_hidden[slot] != 0
                                : !cheapest && now.test_box(view.box) == Visibility::occluded;
        state = hidden ? PairState::hidden_expired : PairState::visible;
    }
}

void InterestManager::test_entities(ClientSlot& c, const RegionVisibility& now,
                                    std::uint32_t viewer, bool cheapest) {
    // 5b. Every entity without a hidden TBV: test its current box (or take its
    //     cluster's answer, step 5a).
    if (!tbvs_enabled_ && !clusters_enabled_ && now.prepared_tests_are_coarse()) {
        test_entities_in_bulk(c, now, viewer, cheapest);
        return;
    }
    if (!tbvs_enabled_ && clusters_enabled_) {
        test_entities_by_cluster(c, now, viewer, cheapest);
        return;
    }
    // Members of the clusters begin_update() made: slots below cluster_of_.size().
    const std::size_t clustered = cluster_of_.size();
    const bool lend_hints = config_.blocker_hints && clusters_enabled_;
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        PairState& state = c.states[slot];
        if (lend_hints && slot < clustered) {
            // Every member of a cluster proven hidden this tick takes its hint, whatever
            // is decided for it below (a member tested on its own tries it first).
            const std::uint32_t member_of = cluster_of_[slot];
            if (member_of != kNoCluster && c.cluster_hidden[member_of] != 0 &&
                c.hints[slot] != c.cluster_hint[member_of]) {
                c.hints[slot] = c.cluster_hint[member_of]; // mostly the same: not written
            }
        }
        if (view_alive_[slot] == 0 || state == PairState::hidden_with_tbv) {
            continue;
        }
        if (slot == viewer) {
            state = PairState::visible;
            continue;
        }
        // The preparation (and the cluster's box) is current unless the box was set
        // after begin_update(); a slot added since has neither (nor a cluster entry).
        const std::uint32_t cluster = view_fresh_[slot] != 0 ? cluster_of_[slot] : kNoCluster;
        if (cluster != kNoCluster && c.cluster_hidden[cluster] != 0) {
            // Hidden with its cluster (whose box holds this one's current box). Without
            // TBVs hide_cluster() would only mark each member as the line below does.
            if (tbvs_enabled_ && c.cluster_hidden[cluster] == 1) {
                c.cluster_hidden[cluster] = 2;
                hide_cluster(c, cluster, viewer);
            }
            if (state != PairState::hidden_with_tbv) {
                state = PairState::hidden_expired; // hide_cluster() made no TBV
            }
            continue;
        }
        test_entity(c, now, slot, cheapest);
    }
}

void InterestManager::test_entities_by_cluster(ClientSlot& c, const RegionVisibility& now,
                                               std::uint32_t viewer, bool cheapest) {
    // test_entities()'s steps for each slot, in another order: no pair holds a TBV, and
    // hide() would only mark the pair. The members of every cluster begin_update() made
    // (each alive slot is in one), then the slots in none.
    const auto on_its_own = [&](std::uint32_t slot) {
        if (view_alive_[slot] == 0) {
            return;
        }
        if (slot == viewer) {
            c.states[slot] = PairState::visible;
            return;
        }
        test_entity(c, now, slot, cheapest);
    };
    for (std::uint32_t k = 0; k < cluster_count_; ++k) {
        const std::vector<std::uint32_t>& members = clusters_[k].members;
        if (members.size() < kMinClusterMembers || c.cluster_hidden[k] == 0) {
            for (const std::uint32_t slot : members) {
                on_its_own(slot);
            }
            continue;
        }
        // Hidden with the cluster, whose box holds each member's box of begin_update():
        // the members whose box has not been set since (view_fresh_, 1 only when alive).
        // Every member takes the hint (one set since tries it first in its own test).
        const std::uint32_t hint = c.cluster_hint[k];
        const bool lend_hint = config_.blocker_hints;
        for (const std::uint32_t slot : members) {
            if (lend_hint) {
                c.hints[slot] = hint;
            }
            if (view_fresh_[slot] != 0 && slot != viewer) {
                c.states[slot] = PairState::hidden_expired;
            } else {
                on_its_own(slot);
            }
        }
    }
    for (const std::uint32_t slot : unlisted_slots_) {
        on_its_own(slot);
    }
    for (auto slot = static_cast<std::uint32_t>(cluster_of_.size()); slot < entities_.size();
         ++slot) {
        on_its_own(slot);
    }
}

void InterestManager::test_entity(ClientSlot& c, const RegionVisibility& now, std::uint32_t slot,
                                  bool cheapest) {
    PairState& state = c.states[slot];
    const bool fresh = view_fresh_[slot] != 0;
    ++c.stats.box_tests;
    const EntitySlot& e = entities_[slot];
    if (cheapest) {
        // A box set after begin_update() has no preparation: visible, never guessed.
        const bool hidden = fresh && now.test_prepared_coarse(e.prepared) == Visibility::occluded;
        state = hidden ? PairState::hidden_expired : PairState::visible;
        return;
    }
    const bool quick = takes_quick_test(c, slot);
    const BoxTest kind = box_test_for(quick, config_.blocker_hints);
    // Without a prepared stage a preparation is the box alone (prepare()), which the
    // packed view holds: the same answers, and the slot, hundreds of bytes from the
    // next, is left unread.
    const bool visible =
        test_current_box(now, kind, e.prepared, views_[slot].box, fresh && prepared_stage_,
                         c.hints[slot]) == Visibility::visible;
    if (!tbvs_enabled_) { // hide() would only mark it: no branch on the answer
        state = visible ? PairState::visible : PairState::hidden_expired;
    } else if (visible) {
        state = PairState::visible;
    } else {
        hide(c, slot);
    }
}

} // namespace dsoc::visibility
