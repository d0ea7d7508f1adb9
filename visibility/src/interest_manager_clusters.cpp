// InterestManager: entity clusters. Entities whose box centres share a cell of
// DSOCConfig::entity_cluster_size are grouped once per tick (begin_update()); one
// test of a cluster's box may then hide all its members from a client (step 5a of
// update_client()), and with TBVs they are hidden together (hide_cluster()).

#include "interest_manager_state.hpp"

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <limits>

namespace dsoc::visibility {

using detail::kMaxTbvAttempts;
using detail::kMinClusterMembers;
using detail::kNoCluster;

void InterestManager::build_clusters() {
    cluster_of_.assign(entities_.size(), kNoCluster);
    unlisted_slots_.clear();
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
            unlisted_slots_.push_back(slot);
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

void InterestManager::test_clusters(ClientSlot& c, const RegionVisibility& now,
                                    std::uint32_t viewer, bool cheapest) {
    // 5a. Clusters with at least two members due a full test: one test of the union
    //     of their boxes may hide them all.
    c.cluster_hidden.assign(cluster_count_, 0);
    c.cluster_hint.resize(cluster_count_); // read only where cluster_hidden is set
    for (std::uint32_t k = 0; k < (cheapest ? 0 : cluster_count_); ++k) {
        const EntityCluster& cluster = clusters_[k];
        if (cluster.members.size() < kMinClusterMembers) {
            continue;
        }
        // Two members due a full test make the test worth it: the count stops there.
        // (view_fresh_, not the slot, for whether its preparation is current: one small
        // array for every member.)
        int due = 0;
        for (std::size_t m = 0; m < cluster.members.size() && due < 2; ++m) {
            const std::uint32_t slot = cluster.members[m];
            const bool decided = c.states[slot] == PairState::hidden_with_tbv || slot == viewer ||
                                 view_fresh_[slot] == 0;
            due += decided || takes_quick_test(c, slot) ? 0 : 1;
        }
        if (due < 2) {
            continue;
        }
        ++c.stats.cluster_tests;
        // Temporal coherence for a cluster, whose members change from tick to tick: what
        // hid it last time was lent to its members (test_entities()), so the hint of a
        // member hidden last tick (what proved it, by itself or with its cluster) is tried
        // first. Not a visible member's: its hint may say that its own last test failed.
        // Any hint is safe (RegionVisibility::test_box_hinted()): it only orders the
        // proofs.
        std::uint32_t hint = 0;
        for (std::size_t m = 0; config_.blocker_hints && m < cluster.members.size(); ++m) {
            const std::uint32_t slot = cluster.members[m];
            const PairState state = c.states[slot];
            if (state == PairState::hidden_expired || state == PairState::hidden_with_tbv) {
                hint = c.hints[slot];
                break;
            }
        }
        const Visibility seen = config_.blocker_hints
                                    ? now.test_prepared_hinted(cluster.prepared, hint)
                                    : now.test_prepared(cluster.prepared);
        if (seen == Visibility::occluded) {
            c.cluster_hidden[k] = 1;
            // What hides the cluster's box hides each member's (inside it): the member's
            // own next test tries it first as well. Lent in test_entities()'s pass (with
            // the member's own state), not here across the pairs.
            c.cluster_hint[k] = hint;
            ++c.stats.cluster_hits;
        }
    }
}

void InterestManager::hide_cluster(ClientSlot& c, std::uint32_t cluster,
                                   std::uint32_t viewer_slot) {
    // Members still undecided this tick (the caller visits them after this call).
    auto& members = c.cluster_members;
    members.clear();
    for (const std::uint32_t slot : clusters_[cluster].members) {
        if (view_alive_[slot] != 0 && slot != viewer_slot &&
            c.states[slot] != PairState::hidden_with_tbv && view_fresh_[slot] != 0) {
            members.push_back(slot);
        }
    }
    // With a prepared stage each member's own TBV costs a few bit tests: no group.
    // (Called with TBVs on only: without them test_entities() marks each member.)
    assert(tbvs_enabled_);
    if (prepared_stage_) {
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
            c.states[slot] = PairState::hidden_expired;
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

} // namespace dsoc::visibility
