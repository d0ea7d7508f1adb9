#include "dsoc/interest/walking_interest.hpp"

#include "dsoc/sim/motion_limits.hpp"

#include <string>
#include <utility>

namespace dsoc::interest {

namespace {

/// Entities never leave the map's bounds by more than this (bots and players stand on
/// its floors; the manager clips TBVs and eye regions to its bounds). [Units: world units]
constexpr float kBoundsMargin = 64.0f;

} // namespace

WalkingInterest::WalkingInterest(const visibility::DSOCConfig& config, const maps::Map& map,
                                 const sim::MoveConfig& move,
                                 visibility::RegionVisibilityFactory make_visibility,
                                 int lookahead_ticks)
    : clipper_(std::make_shared<const sim::ReachClipper>(map.collision_brushes, move)),
      manager_(config, map.bounds.expanded(kBoundsMargin), std::move(make_visibility),
               [clipper = clipper_](glm::vec3 eye, const visibility::Aabb& region,
                                    const visibility::EyeReach& reach) {
                   return clipper->clip(eye, region, reach);
               }) {
    walker_.half_extents = (move.maxs - move.mins) * 0.5f;
    walker_.motion = sim::walking_limits(move, 1.0f / static_cast<float>(config.tick_rate));
    viewer_.eye_motion = walker_.motion;
    viewer_.lookahead_ticks = lookahead_ticks;
    viewer_.enter_leave = false; // the policies answer with the set; replication diffs it
    // The manager's eye is the box centre plus this offset (= origin + eye_height).
    viewer_.eye_offset =
        glm::vec3(0.0f, 0.0f, move.eye_height - (move.mins.z + move.maxs.z) * 0.5f);
}

bool WalkingInterest::add_walker(visibility::EntityId id, const visibility::Aabb& box) {
    return manager_.add_entity(id, walker_, box);
}

bool WalkingInterest::add_viewer(visibility::ClientId client, visibility::EntityId entity) {
    visibility::ClientDesc desc = viewer_;
    desc.viewer = entity;
    return manager_.add_client(client, desc);
}

void WalkingInterest::begin_tick(
    std::uint64_t tick, const std::function<void(visibility::InterestManager&)>& move_entities) {
    if (manager_.config().validate_state) {
        manager_.require_valid_state("before tick " + std::to_string(tick));
    }
    move_entities(manager_);
    manager_.begin_update(tick);
}

} // namespace dsoc::interest
