#pragma once
// The interest manager's view of a culler: conservative visibility from a whole
// region of eyes (a client's reachable eye positions), not from a point.

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <functional>
#include <memory>

namespace dsoc::visibility {

class RegionVisibility {
public:
    virtual ~RegionVisibility() = default;
    /// Prepares answers for eyes anywhere in `region` (a closed box). May reuse memory.
    virtual void build(const Aabb& region) = 0;
    /// `occluded` only when `box` is hidden from EVERY point of the last built region;
    /// `visible` otherwise (may be a false positive). Const and thread-safe after build.
    [[nodiscard]] virtual Visibility test_box(const Aabb& box) const = 0;
    /// A cheaper test with the same guarantee (`occluded` is never wrong) that may
    /// prove less; used for entities that were visible last tick, most of which still
    /// are. Defaults to test_box().
    [[nodiscard]] virtual Visibility test_box_quick(const Aabb& box) const { return test_box(box); }
};

/// Makes one RegionVisibility per client (each client owns its buffer).
using RegionVisibilityFactory = std::function<std::unique_ptr<RegionVisibility>()>;

} // namespace dsoc::visibility
