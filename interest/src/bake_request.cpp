#include "dsoc/interest/bake_request.hpp"

#include "dsoc/sim/player_space.hpp"

namespace dsoc::interest {

maps::BakeRequest walking_bake_request(const sim::MoveConfig& move) {
    maps::BakeRequest request;
    request.player_space = sim::player_space(move, kCoveredReachSeconds);
    return request;
}

} // namespace dsoc::interest
