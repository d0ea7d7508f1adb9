// InterestManager: making a TBV for an entity hidden from a client. How long it may
// last (TbvStrategy), its box, the longest one that is itself hidden, and merging it
// into a group made this tick nearby.

#include "interest_manager_state.hpp"

#include <cstdint>

namespace dsoc::visibility {

using detail::kMaxTbvAttempts;
using detail::kMergeCandidates;
using detail::kMergeExpirySlack;
using detail::kNoGroup;
using detail::kTbvRetryTicks;

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
        c.states[slot] = PairState::hidden_expired;
        return;
    }
    const EntitySlot& e = entities_[slot];
    // The longest TBV that is itself hidden: halve the duration until it is. With a
    // prepared stage (the map's PVS) a TBV is proven by that stage alone, so that
    // re-proving it after each rebuild costs a few bit tests (step 4 of update_client).
    const PreparedBox* found = nullptr;
    int duration = 0;
    std::uint64_t expiry = 0;
    if (prepared_stage_) {
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
        c.states[slot] = PairState::hidden_expired;
        pair.next_tbv_tick = tick_ + kTbvRetryTicks;
        ++c.stats.tbvs_rejected;
        return;
    }
    const PreparedBox& candidate = *found;
    const Aabb box = candidate.box;
    if (expiry <= tick_) {
        c.states[slot] = PairState::hidden_expired;
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
                (prepared_stage_ && (!candidate.prepared || !g.prepared.prepared))) {
                continue;
            }
            Aabb merged = g.box;
            merged.extend(box);
            if (prepared_stage_) {
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

} // namespace dsoc::visibility
