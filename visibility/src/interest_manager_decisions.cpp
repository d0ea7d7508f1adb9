// InterestManager: a client's decisions after its update. The replication set (its
// visible entities), each one's level of detail (update interval by distance from the
// eye region), and the enter/leave lists against the previous set.

#include "interest_manager_state.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

bool InterestManager::keeps(const ClientSlot& c, std::uint32_t slot) const {
    return view_alive_[slot] != 0 &&
           replicated_under(rule_of(c, slot), c.states[slot] == PairState::visible);
}

Relevance InterestManager::rule_of(const ClientSlot& c, std::uint32_t slot) const {
    const std::uint8_t own = c.rules[slot];
    return own != 0 ? static_cast<Relevance>(own - 1) : team_relevance(c.team, view_team_[slot]);
}

std::size_t InterestManager::kept_by_sixteen(const ClientSlot& c, std::uint32_t* kept,
                                             std::uint32_t& slot) const {
    std::size_t count = 0;
#if defined(__SSE2__)
    // decide()'s rule, sixteen slots to an instruction: kept when alive and
    // replicated_under(rule_of()): the pair's own rule (c.rules: 1 + a Relevance), or
    // with none the team rule (team_relevance(): always for a teammate, else sight).
    // Tests: Relevance.* hold it to the model of the rules, slots on either side of 16.
    const std::size_t n = entities_.size();
    const __m128i zero = _mm_setzero_si128();
    const __m128i seen_state = _mm_set1_epi8(static_cast<char>(PairState::visible));
    const __m128i own_sight =
        _mm_set1_epi8(static_cast<char>(1 + static_cast<int>(Relevance::sight)));
    const __m128i own_always =
        _mm_set1_epi8(static_cast<char>(1 + static_cast<int>(Relevance::always)));
    const __m128i team = _mm_set1_epi16(static_cast<short>(c.team));
    const bool has_team = c.team != kNoTeam;
    const auto load = [](const void* p) { return _mm_loadu_si128(static_cast<const __m128i*>(p)); };
    for (; slot + 16 <= n; slot += 16) {
        const __m128i seen = _mm_cmpeq_epi8(load(c.states.data() + slot), seen_state);
        const __m128i own = load(c.rules.data() + slot);
        const __m128i alive = _mm_cmpgt_epi8(load(view_alive_.data() + slot), zero);
        const __m128i mate =
            has_team ? _mm_packs_epi16(_mm_cmpeq_epi16(load(view_team_.data() + slot), team),
                                       _mm_cmpeq_epi16(load(view_team_.data() + slot + 8), team))
                     : zero;
        const __m128i by_team = _mm_cmpeq_epi8(own, zero);
        const __m128i always =
            _mm_or_si128(_mm_cmpeq_epi8(own, own_always), _mm_and_si128(by_team, mate));
        const __m128i sight =
            _mm_or_si128(_mm_cmpeq_epi8(own, own_sight), _mm_andnot_si128(mate, by_team));
        const __m128i keep = _mm_and_si128(alive, _mm_or_si128(always, _mm_and_si128(sight, seen)));
        for (auto mask = static_cast<unsigned>(_mm_movemask_epi8(keep)); mask != 0;
             mask &= mask - 1) {
            kept[count++] = slot + static_cast<std::uint32_t>(std::countr_zero(mask));
        }
    }
#else
    (void)c;
    (void)kept;
    (void)slot;
#endif
    return count;
}

void InterestManager::decide(ClientSlot& c) {
    ClientDecisions& d = c.decisions;
    const float near_squared = config_.lod_near_distance * config_.lod_near_distance;
    const float far_squared = config_.lod_far_distance * config_.lod_far_distance;
    const Aabb region = c.region; // a local: the writes below cannot alias it
    // First the kept slots: alive, and replicated under the pair's rule given what the
    // culler decided. Sixteen at a time where there is SSE2 (kept_by_sixteen(), the same
    // rule), then one at a time, branch-free (whether a slot is kept is a coin toss for
    // the branch predictor): each slot is written at the end and the end moves when kept.
    std::vector<std::uint32_t>& kept = c.kept_slots;
    kept.resize(entities_.size());
    std::uint32_t slot = 0;
    std::size_t count = kept_by_sixteen(c, kept.data(), slot);
    for (; slot < entities_.size(); ++slot) {
        kept[count] = slot;
        count += static_cast<std::size_t>(keeps(c, slot));
    }
    kept.resize(count);
    if (config_.validate_state) {
        // The slow twin of kept_by_sixteen(): the rule slot by slot, every slot.
        std::size_t k = 0;
        bool same = true;
        for (std::uint32_t s = 0; s < entities_.size(); ++s) {
            if (keeps(c, s)) {
                same = same && k < count && kept[k] == s;
                ++k;
            }
        }
        if (!same || k != count) {
            throw std::logic_error("invalid DSOC state in decide(): client " +
                                   std::to_string(c.id) +
                                   ": the slots kept sixteen at a time are not the rule's");
        }
    }
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
    if (!c.desc.enter_leave) {
        return; // enter and leave stay empty, and `previous` unused
    }
    diff_sets(c.previous, d.replicated, d.enter, d.leave);
    c.previous.clear();
    for (const auto& r : d.replicated) {
        c.previous.push_back(r.id);
    }
}

} // namespace dsoc::visibility
