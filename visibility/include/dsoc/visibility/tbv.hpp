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
    /// Bound on the downward speed (falls).
    float down_speed = 800.0f;
};

/// The box `box` can sweep within `seconds`: grown by horizontal_speed * seconds on
/// x and y, up_speed * seconds above and down_speed * seconds below, then every
/// growth scaled by `expansion` (>= 1, a safety margin). Axis-separable, so it
/// contains the exact reachable set (a disc is inside its bounding square).
[[nodiscard]] Aabb reachable_box(const Aabb& box, const MotionLimits& limits, float seconds,
                                 float expansion = 1.0f);

/// The farthest a point moving within `limits` can get in `seconds`, per direction:
/// x and y use horizontal_speed, z up/down the vertical speeds. Used to detect jumps
/// beyond the bound (teleports).
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
