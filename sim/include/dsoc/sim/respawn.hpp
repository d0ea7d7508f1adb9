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

namespace dsoc::sim {

struct PendingRespawn {
    MoveState arrival;        ///< the state it will be put in: at the spawn point, at rest
    float yaw_degrees = 0.0f; ///< the spawn point's facing
    int ticks_left = 0;       ///< world steps until it is put there; >= 1 while pending
};

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
