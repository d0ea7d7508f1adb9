#pragma once
// DSOC interest management for players who walk by sim::MoveConfig's rules. A walking
// player is an InterestManager entity with the player's box and the motion limits of
// walking at the tick rate (sim::walking_limits), and, when a client views from it, a
// client whose eye is at the player's eye height, moves by the same limits, and is
// covered for `lookahead_ticks` (its latency allowance). Eye regions are clipped to
// what walking can reach from the eye (sim::ReachClipper: no walking through walls,
// no falling faster than gravity where no slope is in reach).
//
// Threading: as InterestManager (begin_tick() serial; update_client() per client).

#include "dsoc/maps/map.hpp"
#include "dsoc/sim/player_move.hpp"
#include "dsoc/sim/reach_clipper.hpp"
#include "dsoc/visibility/interest_manager.hpp"

#include <cstdint>
#include <functional>
#include <memory>

namespace dsoc::interest {

class WalkingInterest {
public:
    /// `config` must pass visibility::validate(); `make_visibility` makes each client's
    /// culler (make_culler(); may be empty when no client is added, e.g. to ask
    /// eye_region() alone); `lookahead_ticks` >= 0.
    WalkingInterest(const visibility::DSOCConfig& config, const maps::Map& map,
                    const sim::MoveConfig& move,
                    visibility::RegionVisibilityFactory make_visibility, int lookahead_ticks);

    /// A walking player (or bot) with id `id` whose box is `box` now.
    bool add_walker(visibility::EntityId id, const visibility::Aabb& box);
    /// A client viewing from walker `entity`. Its decisions hold `replicated` only
    /// (ClientDesc::enter_leave off: the policies answer with the whole set).
    bool add_viewer(visibility::ClientId client, visibility::EntityId entity);
    /// Begins tick `tick`, in this order: checks the manager's invariants of the last
    /// tick (ValidateDSOCState) when DSOCConfig::validate_state is on, before anything
    /// moved; calls `move_entities` to add, remove and move this tick's entities; then
    /// begin_update(). (After the moves, a box may lawfully have left a fuzzy TBV:
    /// update_client() catches that, so the check must come first.)
    void begin_tick(std::uint64_t tick,
                    const std::function<void(visibility::InterestManager&)>& move_entities);

    /// Every eye a walking viewer at `eye`, falling at `down_velocity` (units/s, >= 0),
    /// can reach over its lookahead: the region its culler must cover (the manager's
    /// rule, InterestManager::reachable_eye_region()).
    [[nodiscard]] visibility::Aabb eye_region(glm::vec3 eye, float down_velocity) const {
        return manager_.reachable_eye_region(viewer_, eye, down_velocity);
    }

    [[nodiscard]] visibility::InterestManager& manager() { return manager_; }
    [[nodiscard]] const visibility::InterestManager& manager() const { return manager_; }
    [[nodiscard]] const visibility::EntityDesc& walker() const { return walker_; }
    [[nodiscard]] const visibility::ClientDesc& viewer() const { return viewer_; }

private:
    std::shared_ptr<const sim::ReachClipper> clipper_;
    visibility::InterestManager manager_;
    visibility::EntityDesc walker_;
    visibility::ClientDesc viewer_;
};

} // namespace dsoc::interest
