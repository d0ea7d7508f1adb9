// InterestManager: the invariant checker (ValidateDSOCState). Reads the state, changes
// nothing.

#include "interest_manager_state.hpp"

#include <stdexcept>
#include <string>

namespace dsoc::visibility {

using detail::kNoGroup;

std::vector<std::string> InterestManager::validate_state() const {
    std::vector<std::string> problems;
    const auto say = [&](ClientId c, EntityId e, const std::string& what) {
        problems.push_back("client " + std::to_string(c) + ", entity " + std::to_string(e) + ": " +
                           what);
    };
    const std::size_t n = entities_.size();
    if (views_.size() != n || view_alive_.size() != n || view_team_.size() != n ||
        view_fresh_.size() != n) {
        problems.push_back("the packed views do not cover every entity slot");
        return problems; // the checks below index them by slot
    }
    for (const auto& cp : clients_) {
        if (cp->states.size() != n || cp->rules.size() != n || cp->hints.size() != n ||
            cp->pairs.size() != n) {
            problems.push_back("client " + std::to_string(cp->id) +
                               ": its per-entity arrays do not cover every entity slot");
            return problems;
        }
    }
    for (std::uint32_t slot = 0; slot < entities_.size(); ++slot) {
        const EntitySlot& e = entities_[slot];
        const EntityView& v = views_[slot];
        if ((view_alive_[slot] != 0) != e.alive ||
            (view_fresh_[slot] != 0) != (e.alive && e.prepared_is_current()) ||
            (e.alive && (v.id != e.id || v.box.min != e.box.min || v.box.max != e.box.max))) {
            problems.push_back("entity slot " + std::to_string(slot) +
                               ": its packed view disagrees with the slot");
        }
    }
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
                if (c.pairs[slot].group != g || c.states[slot] != PairState::hidden_with_tbv) {
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
                if (c.states[slot] != PairState::unknown || pair.group != kNoGroup) {
                    problems.push_back("client " + std::to_string(c.id) +
                                       ": state kept for a removed entity");
                }
                continue;
            }
            if (c.states[slot] == PairState::visible && pair.group != kNoGroup) {
                say(c.id, e.id, "visible but holds a TBV");
            }
            if (c.states[slot] != PairState::hidden_with_tbv) {
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

void InterestManager::require_valid_state(const std::string& when) const {
    const auto problems = validate_state();
    if (!problems.empty()) {
        throw std::logic_error("ValidateDSOCState " + when + ": " + problems.front() + " (and " +
                               std::to_string(problems.size() - 1) + " more)");
    }
}

} // namespace dsoc::visibility
