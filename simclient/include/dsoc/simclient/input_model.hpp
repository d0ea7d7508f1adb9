#pragma once
// What a simulated player wants to do each tick, by behaviour: wanderers hold a random
// heading 1-3 s then pick another; campers stand still, now and then take a short small
// step (0.2-0.5 s at a third of full speed, every 2-5 s) and sweep their view slowly.

#include "dsoc/protocol/messages.hpp"
#include "dsoc/simclient/scenario.hpp"

#include <random>

namespace dsoc::simclient {

class InputModel {
public:
    InputModel(Behaviour behaviour, std::uint64_t seed);

    /// Fills the movement and view of the next input (not its tick).
    void next(protocol::pb::ClientInput& input, int tick_rate);

private:
    void wander(protocol::pb::ClientInput& input, int tick_rate);
    void camp(protocol::pb::ClientInput& input, int tick_rate);

    Behaviour behaviour_;
    std::mt19937_64 rng_;
    float yaw_deg_ = 0.0f;
    int ticks_left_ = 0;    // of the current heading (wanderer) or pause or step (camper)
    bool stepping_ = true;  // camper: in a step (the first toggle starts with a pause)
    float view_deg_ = 0.0f; // camper: the sweeping view
};

} // namespace dsoc::simclient
