// InterestManager: a client's decisions after its update. The replication set (its
// visible entities), each one's level of detail (update interval by distance from the
// eye region), and the enter/leave lists against the previous set.

#include "interest_manager_state.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::visibility {

namespace {

/// Distance between the nearest points of `region` and `box` (0 when they touch):
/// no eye the client can reach is nearer to the entity. [Units: world units]
float conservative_distance(const Aabb& region, const Aabb& box) {
    const glm::vec3 gap =
        glm::max(glm::vec3(0.0f), glm::max(region.min - box.max, box.min - region.max));
    return std::sqrt(glm::dot(gap, gap));
}

/// The level of detail for an entity `distance` from the eye region: every tick near
/// (lod_near_distance), every other tick between, every fourth tick beyond
/// lod_far_distance. How coarse each tier's positions are is the user's to choose (the
/// server's position_quantum_near/mid/far).
void set_level_of_detail(Replicated& r, float distance, const DSOCConfig& config) {
    if (distance < config.lod_near_distance) {
        r.update_interval = 1;
    } else if (distance < config.lod_far_distance) {
        r.update_interval = 2;
    } else {
        r.update_interval = 4;
    }
}

/// Ids in `previous` and not in `now` go to `leave`, the reverse to `enter`. Both
/// inputs increasing; so are the outputs.
void diff_sets(const std::vector<EntityId>& previous, const std::vector<Replicated>& now,
               std::vector<EntityId>& enter, std::vector<EntityId>& leave) {
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < previous.size() || j < now.size()) {
        if (j == now.size() || (i < previous.size() && previous[i] < now[j].id)) {
            leave.push_back(previous[i++]);
        } else if (i == previous.size() || now[j].id < previous[i]) {
            enter.push_back(now[j++].id);
        } else {
            ++i;
            ++j;
        }
    }
}

} // namespace

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
        set_level_of_detail(r, conservative_distance(c.region, e.box), config_);
        d.replicated.push_back(r);
    }
    std::sort(d.replicated.begin(), d.replicated.end(),
              [](const Replicated& a, const Replicated& b) { return a.id < b.id; });
    diff_sets(c.previous, d.replicated, d.enter, d.leave);
    c.previous.clear();
    for (const auto& r : d.replicated) {
        c.previous.push_back(r.id);
    }
}

} // namespace dsoc::visibility
