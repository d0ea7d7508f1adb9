#pragma once
// Respawns the world decides ahead of time. A respawn puts an entity where its
// movement could never take it (a teleport), so no motion limit covers the eyes after
// it. The world therefore picks the spawn point at the moment of death and puts the
// entity there only `ticks_left` steps later; until then it lies where it died, at
// rest. A client whose respawn is pending may be sent what it will see from the spawn
// point before it is there (interest::Viewer::arrival_eye): with a delay of at least
// the client's latency allowance in ticks, no respawn inside the allowance is a
// surprise, and none pops entities in.

#include "dsoc/sim/player_move.hpp"

#include <optional>

namespace dsoc::sim {

struct PendingRespawn {
    MoveState arrival;        ///< the state it will be put in: at the spawn point, at rest
    float yaw_degrees = 0.0f; ///< the spawn point's facing
    int ticks_left = 0;       ///< world steps until it is put there; >= 1 while pending
};

/// A death decided in this step: the entity goes to `arrival` (facing `yaw_degrees`)
/// `delay_ticks` steps from now. With a delay, `pending` is set and `state` stays where
/// it died, at rest; returns false. Without one (<= 0), `state` is put at the arrival at
/// once; returns true (the teleport).
inline bool die(MoveState& state, const MoveState& arrival, float yaw_degrees, int delay_ticks,
                std::optional<PendingRespawn>& pending) {
    if (delay_ticks <= 0) {
        state = arrival;
        return true;
    }
    pending = PendingRespawn{arrival, yaw_degrees, delay_ticks};
    state.velocity = glm::vec3(0.0f);
    return false;
}

/// One world step of a dead entity: counts `pending` down and, when it reaches 0, puts
/// `state` at the arrival and returns true (the teleport); otherwise keeps the entity
/// where it died, at rest, and returns false. Precondition: pending.ticks_left >= 1.
inline bool step_dead(PendingRespawn& pending, MoveState& state) {
    if (--pending.ticks_left > 0) {
        state.velocity = glm::vec3(0.0f);
        return false;
    }
    state = pending.arrival;
    return true;
}

} // namespace dsoc::sim
