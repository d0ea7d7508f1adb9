#pragma once
// The one bake request the server, the evaluation and dsoc-bake make for a map whose
// players walk by sim::MoveConfig's rules, so that all three file the same table under
// the same key: the bake's defaults over the space walkers can be in.

#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/sim/player_move.hpp"

namespace dsoc::interest {

/// The latency allowance the covered space is made for: eye regions of longer
/// allowances may reach cells the table does not cover, where it answers nothing
/// (conservative; the table saves nothing there). [Units: s]
inline constexpr float kCoveredReachSeconds = 0.25f;

/// Default bake settings over sim::player_space(move, kCoveredReachSeconds).
[[nodiscard]] maps::BakeRequest walking_bake_request(const sim::MoveConfig& move = {});

} // namespace dsoc::interest
