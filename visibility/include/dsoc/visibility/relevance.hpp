#pragma once
// Interest beyond sight: why a client may be sent an entity it cannot see, or be
// denied one it can. A (client, entity) pair is under one rule; the default is sight
// (the culler decides). A teammate, the client's own projectile or an objective is
// `always` sent; an object only spectators may know of is `never` sent. Teams give
// the common case without a rule per pair: an entity of the client's team (both not
// kNoTeam) is `always` sent unless a pair rule says otherwise.
//
// The conservative guarantee (docs/dsoc.md) is about `sight` pairs; `always` pairs are
// sent whether seen or not (so never popped in), `never` pairs are not sent at all
// (the game's choice, outside the guarantee).

#include <cstdint>
#include <string_view>

namespace dsoc::visibility {

enum class Relevance : std::uint8_t {
    sight,  ///< sent when the culler cannot prove it hidden (the default)
    always, ///< sent, seen or not
    never,  ///< not sent, seen or not
};

/// Names for settings, traces and messages: "sight", "always", "never".
[[nodiscard]] constexpr std::string_view name_of(Relevance r) {
    return r == Relevance::always ? "always" : (r == Relevance::never ? "never" : "sight");
}

using TeamId = std::uint16_t;
inline constexpr TeamId kNoTeam = 0;

/// The rule of a pair with no pair rule of its own: always for teammates, else sight.
[[nodiscard]] constexpr Relevance team_relevance(TeamId client_team, TeamId entity_team) {
    return client_team != kNoTeam && client_team == entity_team ? Relevance::always
                                                                : Relevance::sight;
}

/// Whether a pair under `rule` is replicated when sight says `seen`.
[[nodiscard]] constexpr bool replicated_under(Relevance rule, bool seen) {
    return rule == Relevance::always || (rule == Relevance::sight && seen);
}

} // namespace dsoc::visibility
