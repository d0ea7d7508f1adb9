// InterestManager: each client's pool of TBV groups. A group holds the TBVs of one or
// more hidden entities under one box until its expiry; it lives in the client's
// octree (re-proving after a rebuild) and expiry heap. Freed groups are reused; at
// max_tbvs_per_client the group that expires first is evicted.

#include "interest_manager_state.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>

namespace dsoc::visibility {

using detail::kNoGroup;

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
    c.states[slot] = PairState::hidden_with_tbv;
    c.pairs[slot].group = group;
    tbv_counts_[slot].fetch_add(1, std::memory_order_relaxed);
    ++c.stats.tbvs_created;
}

std::size_t InterestManager::expire_earliest_group(ClientSlot& c) {
    const auto top = c.expiries.top();
    c.expiries.pop();
    TbvGroup& g = c.groups[top.group];
    if (!g.alive || g.generation != top.generation) {
        return 0; // stale heap entry: the group was freed or reused since
    }
    for (const std::uint32_t slot : g.members) {
        c.states[slot] = PairState::hidden_expired;
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

} // namespace dsoc::visibility
