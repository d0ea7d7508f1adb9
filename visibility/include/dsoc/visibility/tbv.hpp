#pragma once
// Temporal Bounding Volumes: the region an entity can reach within a time span,
// from its declared motion limits (Sudarsky & Gotsman's DSOC). A TBV is a promise
// only as good as those limits: an entity that moves faster voids it (the manager
// detects jumps beyond the bound and re-tests).

#include "dsoc/visibility/geometry.hpp"

#include <array>
#include <cstdint>

namespace dsoc::visibility {

/// How fast an entity (or a viewer's eye) can move. [Units: world units / s] [Limit: >= 0]
struct MotionLimits {
    /// Bound on the speed in the horizontal (x, y) plane.
    float horizontal_speed = 320.0f;
    /// Bound on the upward speed (jumps, stairs, lifts).
    float up_speed = 320.0f;
    /// Bound on the downward speed (falls: the terminal speed).
    float down_speed = 800.0f;
    /// Downward acceleration when known (> 0): a fall that starts at downward speed v0
    /// covers at most v0 * t + gravity * t^2 / 2. 0: use down_speed alone.
    /// [Units: world units / s^2] [Limit: >= 0]
    float gravity = 0.0f;
    /// With gravity only: the downward speed a fall may start from whatever the current
    /// one is (walking down the steepest walkable ground needs no gravity to get there).
    /// [Units: world units/s] [Limit: >= 0]
    float fall_speed_floor = 0.0f;
    /// With gravity only: added to the starting downward speed for movement stepped in
    /// ticks of dt (velocity first, then position: gravity * dt / 2 more per second
    /// than the continuous law). [Units: world units/s] [Limit: >= 0]
    float fall_speed_margin = 0.0f;
    /// Distance added above whatever the time (e.g. a step-up a movement code may take
    /// in one move). [Units: world units] [Limit: >= 0]
    float vertical_slack = 0.0f;
    /// Distance added below whatever the time (e.g. a step-down, or float rounding of
    /// positions far from the origin). [Units: world units] [Limit: >= 0]
    float fall_slack = 0.0f;
};

/// How far an entity moving within `limits` can fall in `seconds`, not counting
/// fall_slack: down_speed * seconds, or, when gravity > 0 and the current downward
/// speed `down_velocity` (>= 0) is known, the smaller of that and
/// (max(down_velocity, fall_speed_floor) + fall_speed_margin) * t + gravity * t^2 / 2.
/// [Units: world units]
[[nodiscard]] float fall_bound(const MotionLimits& limits, float seconds, float down_velocity);

/// The box `box` can sweep within `seconds`: grown by horizontal_speed * seconds on
/// x and y, up_speed * seconds + vertical_slack above and the fall bound + fall_slack
/// below, then every growth scaled by `expansion` (>= 1, a safety
/// margin). The fall bound is fall_bound(); pass a negative down_velocity when unknown.
/// Axis-separable, so it contains the exact reachable set (a disc is inside its
/// bounding square).
[[nodiscard]] Aabb reachable_box(const Aabb& box, const MotionLimits& limits, float seconds,
                                 float expansion = 1.0f, float down_velocity = -1.0f);

/// The farthest a point moving within `limits` can get in `seconds`, per direction:
/// x and y use horizontal_speed, z up/down the vertical speeds. Used to detect jumps
/// beyond the bound (teleports). `tolerance` absorbs float noise. [Units: world units]
[[nodiscard]] bool within_reach(glm::vec3 from, glm::vec3 to, const MotionLimits& limits,
                                float seconds, float tolerance);

/// Recent positions of an entity's box centre, one per tick, newest last. Feeds the
/// fuzzy (predictive, NOT conservative) TBV strategy.
class MovementHistory {
public:
    static constexpr int kCapacity = 8;
    void push(glm::vec3 center);
    void clear() { count_ = 0; }
    [[nodiscard]] int size() const { return count_; }
    /// i = 0 is the oldest kept sample.
    [[nodiscard]] glm::vec3 at(int i) const;

private:
    std::array<glm::vec3, kCapacity> samples_{};
    int head_ = 0; ///< index of the next write
    int count_ = 0;
};

/// Fuzzy TBV: extrapolates the history at its mean velocity for `ticks` ticks and
/// keeps `confidence` (0.5..0.999) of the spread of the history's residuals around
/// that line, growing as sqrt(t). Cheap and often much tighter than the
/// conservative box, but an entity that turns sharply can leave it: never the
/// default, and the evaluation reports its violations. With fewer than 2 samples it
/// falls back to reachable_box.
[[nodiscard]] Aabb fuzzy_box(const Aabb& box, const MovementHistory& history, int ticks,
                             float tick_seconds, float confidence, const MotionLimits& limits);

} // namespace dsoc::visibility
