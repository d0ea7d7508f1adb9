// InterestManager: a client's decisions after its update. The replication set (its
// visible entities), each one's level of detail (update interval by distance from the
// eye region), and the enter/leave lists against the previous set.

#include "interest_manager_state.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace dsoc::visibility {

namespace {

/// max(0, v) by its sign bit, without a compare: the compiler turns a compare with 0
/// that feeds a square into a branch on the sign, which is a coin toss from entity to
/// entity. (A negative NaN gives 0, a positive one stays NaN.)
float zero_if_negative(float v) {
    const auto bits = std::bit_cast<std::int32_t>(v);
    return std::bit_cast<float>(bits & ~(bits >> 31)); // >> 31: all ones when negative
}

/// Squared distance between the nearest points of `region` and `box` (0 when they
/// touch): no eye the client can reach is nearer to the entity. [Units: world units²]
float conservative_distance_squared(const Aabb& region, const Aabb& box) {
    const auto gap = [](float region_min, float region_max, float box_min, float box_max) {
        return zero_if_negative(std::max(region_min - box_max, box_min - region_max));
    };
    const float x = gap(region.min.x, region.max.x, box.min.x, box.max.x);
    const float y = gap(region.min.y, region.max.y, box.min.y, box.max.y);
    const float z = gap(region.min.z, region.max.z, box.min.z, box.max.z);
    return x * x + y * y + z * z;
}

/// The level of detail for an entity whose squared distance from the eye region is
/// `distance_squared`: every tick near (lod_near_distance), every other tick between,
/// every fourth tick beyond lod_far_distance. How coarse each tier's positions are is
/// the user's to choose (the server's position_quantum_near/mid/far).
std::uint8_t level_of_detail(float distance_squared, float near_squared, float far_squared) {
    const std::uint8_t beyond_near = distance_squared < far_squared ? 2 : 4;
    return distance_squared < near_squared ? 1 : beyond_near;
}

/// Ids in `previous` and not in `now` go to `leave`, the reverse to `enter`. Both
/// inputs increasing; so are the outputs. Branch-free while both lists last (which
/// list holds the smaller id is a coin toss): each step writes both candidates and
/// keeps the one that is not in the other list.
void diff_sets(const std::vector<EntityId>& previous, const std::vector<Replicated>& now,
               std::vector<EntityId>& enter, std::vector<EntityId>& leave) {
    enter.resize(now.size());
    leave.resize(previous.size());
    std::size_t i = 0;
    std::size_t j = 0;
    std::size_t entered = 0;
    std::size_t left = 0;
    while (i < previous.size() && j < now.size()) {
        const EntityId a = previous[i];
        const EntityId b = now[j].id;
        leave[left] = a;
        enter[entered] = b;
        left += a < b ? 1 : 0;
        entered += b < a ? 1 : 0;
        i += a <= b ? 1 : 0;
        j += b <= a ? 1 : 0;
    }
    for (; i < previous.size(); ++i) {
        leave[left++] = previous[i];
    }
    for (; j < now.size(); ++j) {
        enter[entered++] = now[j].id;
    }
    enter.resize(entered);
    leave.resize(left);
}

} // namespace

Relevance InterestManager::rule_of(const ClientSlot& c, std::uint32_t slot) const {
    const std::uint8_t own = c.rules[slot];
    return own != 0 ? static_cast<Relevance>(own - 1) : team_relevance(c.team, views_[slot].team);
}

void InterestManager::decide(ClientSlot& c) {
    ClientDecisions& d = c.decisions;
    const float near_squared = config_.lod_near_distance * config_.lod_near_distance;
    const float far_squared = config_.lod_far_distance * config_.lod_far_distance;
    const Aabb region = c.region; // a local: the writes below cannot alias it
    // First the kept slots, branch-free (whether a slot is kept is a coin toss for the
    // branch predictor): each slot is written at the end and the end moves when kept.
    std::vector<std::uint32_t>& kept = c.kept_slots;
    kept.resize(entities_.size());
    std::size_t count = 0;
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        kept[count] = slot;
        count += static_cast<std::size_t>(views_[slot].alive) *
                 static_cast<std::size_t>(
                     replicated_under(rule_of(c, slot), c.states[slot] == PairState::visible));
    }
    kept.resize(count);
    d.replicated.resize(count);
    bool increasing = true; // slots are reused, so ids need not follow slot order
    EntityId last = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const EntityView& e = views_[kept[k]];
        increasing = increasing && (k == 0 || last < e.id);
        last = e.id;
        d.replicated[k] = {e.id, level_of_detail(conservative_distance_squared(region, e.box),
                                                 near_squared, far_squared)};
    }
    if (!increasing) {
        std::sort(d.replicated.begin(), d.replicated.end(),
                  [](const Replicated& a, const Replicated& b) { return a.id < b.id; });
    }
    diff_sets(c.previous, d.replicated, d.enter, d.leave);
    c.previous.clear();
    for (const auto& r : d.replicated) {
        c.previous.push_back(r.id);
    }
}

} // namespace dsoc::visibility
