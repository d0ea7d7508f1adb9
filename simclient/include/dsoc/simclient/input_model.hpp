#pragma once
// What a simulated player wants to do each tick, by behaviour: wanderers hold a random
// heading 1-3 s then pick another and fire now and then (0.5 shots a second, so
// other clients hear shots); campers stand still, now and then take a short small
// step (0.2-0.5 s at a third of full speed, every 2-5 s) and sweep their view slowly;
// spectators stand still and watch a player entity they know (not their own), another
// every 5-10 s or as soon as the watched one is gone from their replica.

#include "dsoc/protocol/messages.hpp"
#include "dsoc/simclient/scenario.hpp"

#include <cstdint>
#include <random>
#include <vector>

namespace dsoc::simclient {

/// What the input model asks of a client's replica, whichever decoder holds it.
class KnownEntities {
public:
    virtual ~KnownEntities() = default;
    [[nodiscard]] virtual bool knows(std::uint32_t id) const = 0;
    /// Appends the ids of the player entities known (EntityState.kind 1), in any order.
    virtual void players(std::vector<std::uint32_t>& out) const = 0;
};

class InputModel {
public:
    InputModel(Behaviour behaviour, std::uint64_t seed);

    /// Fills the movement, view and watched entity of the next input (not its tick).
    /// `replica`: what the client knows now; `own_entity`: its own entity's id.
    void next(protocol::pb::ClientInput& input, int tick_rate, const KnownEntities& replica,
              std::uint32_t own_entity);

private:
    void wander(protocol::pb::ClientInput& input, int tick_rate);
    void camp(protocol::pb::ClientInput& input, int tick_rate);
    void spectate(protocol::pb::ClientInput& input, int tick_rate, const KnownEntities& replica,
                  std::uint32_t own_entity);

    Behaviour behaviour_;
    std::mt19937_64 rng_;
    float yaw_deg_ = 0.0f;
    int ticks_left_ = 0;      // of the current heading (wanderer) or pause or step (camper)
    bool stepping_ = true;    // camper: in a step (the first toggle starts with a pause)
    float view_deg_ = 0.0f;   // camper: the sweeping view
    std::uint32_t watch_ = 0; // spectator: the watched entity (0: none known yet)
    std::vector<std::uint32_t> players_; // spectator: scratch, the players it knows
};

} // namespace dsoc::simclient
