#pragma once
// What one client knows at one tick, as the inspector draws it: where its eye is,
// where it can move within its latency allowance, and each other entity's state.
// Filled either from a live in-process simulation (live_source.hpp) or from a
// replication trace (trace_source.hpp).

#include "dsoc/visibility/geometry.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace dsoc::inspect {

/// How an entity stands for the inspected client.
enum class EntityState : std::uint8_t {
    /// Replicated, and the culler cannot prove it hidden from the present eye (it may
    /// still be hidden: culler answers err towards visible).
    replicated_visible,
    /// Replicated, proven hidden from the present eye but not from every eye the
    /// client can reach within its latency allowance: sent because of the lookahead.
    replicated_lookahead,
    /// Replicated although the culler now proves it hidden from the whole reachable
    /// eye region: kept until its next full test (dsoc re-tests visible entities
    /// only every few ticks) or because the manager's culling region is the reused,
    /// larger one.
    replicated_held,
    /// Replicated by a rule beyond sight, whatever it sees: a teammate, or a pair rule
    /// `always` (visibility::Relevance).
    replicated_rule,
    /// Replicated only because the client hears it: a coarse position, no view angles
    /// (interest::Hearing).
    replicated_heard,
    /// Not replicated; its Temporal Bounding Volume is hidden from the client.
    hidden_tbv,
    /// Not replicated and no valid TBV: its box is tested every tick.
    hidden_expired,
    /// Not replicated, no more known (a trace records no TBVs; or a new pair).
    not_replicated,
};

/// Every state, sent ones first.
inline constexpr EntityState kEveryEntityState[] = {
    EntityState::replicated_visible, EntityState::replicated_lookahead,
    EntityState::replicated_held,    EntityState::replicated_rule,
    EntityState::replicated_heard,   EntityState::hidden_tbv,
    EntityState::hidden_expired,     EntityState::not_replicated};

[[nodiscard]] const char* to_string(EntityState s) noexcept;

struct EntityView {
    std::uint32_t id = 0;
    visibility::Aabb box;
    EntityState state = EntityState::not_replicated;
    /// The TBV holding the entity (hidden_tbv only; empty otherwise).
    visibility::Aabb tbv;
};

struct ClientView {
    std::uint64_t tick = 0;
    std::uint32_t client = 0;
    glm::vec3 eye{0.0f};
    /// Every eye the client can reach within its latency allowance, as the interest
    /// manager computed it; empty when unknown (traces do not record it).
    visibility::Aabb eye_region;
    /// The entity the client controls, if any (drawn as the viewer, not listed below).
    std::optional<std::uint32_t> viewer_entity;
    visibility::Aabb viewer_box;
    /// Every other entity, in increasing id order.
    std::vector<EntityView> entities;

    /// How many entities are in state `s`.
    [[nodiscard]] std::size_t count(EntityState s) const;
};

} // namespace dsoc::inspect
