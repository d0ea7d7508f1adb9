#pragma once
// The space a walker under MoveConfig's rules can be in, and look from, in the terms of
// a baked cell table's coverage (maps::PlayerSpace): above walkable ground, up to the
// top of its box or of its eye region at a jump's apex.

#include "dsoc/maps/player_space.hpp"
#include "dsoc/sim/player_move.hpp"

namespace dsoc::sim {

/// The player space of walkers under `move` whose eye regions cover up to
/// `reach_seconds` of movement (a viewer's latency allowance):
/// - height: from the ground, the higher of the box's top and the eye region's top,
///   with the walker at a jump's apex plus one step (the climb credit), and the eye
///   region reaching motion_bound(move, reach_seconds).up above the eye;
/// - margin: motion_bound(...).horizontal plus the box's largest horizontal half
///   extent, so that an eye region or box beside a ledge is still covered.
/// Where a walker is elsewhere (falling far, thrown by a trigger), a table answers
/// nothing: conservative, the exact stages or "visible" answer there.
/// [Units: s] [Limit: reach_seconds >= 0]
[[nodiscard]] maps::PlayerSpace player_space(const MoveConfig& move, float reach_seconds);

} // namespace dsoc::sim
