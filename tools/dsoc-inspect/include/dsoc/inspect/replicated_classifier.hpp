#pragma once
// Why is a replicated entity replicated? Runs the server's own culler (the map's PVS
// stage, then the occluder culler) once from the present eye and once from the
// client's reachable eye region, and sorts a replicated box into
// replicated_visible / replicated_lookahead / replicated_held (client_view.hpp).
// "Visible" is the culler's conservative answer: it may be hidden in truth.

#include "dsoc/inspect/client_view.hpp"
#include "dsoc/maps/pvs.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <memory>

namespace dsoc::inspect {

class ReplicatedClassifier {
public:
    /// `pvs` may be null (no PVS stage). Both are shared, read-only.
    ReplicatedClassifier(std::shared_ptr<const visibility::OccluderScene> scene,
                         std::shared_ptr<const maps::Pvs> pvs,
                         const visibility::RegionCullerConfig& culler);

    /// Builds both cullers: from `eye` and from `eye_region` (empty: unknown, then
    /// nothing is called held).
    void prepare(glm::vec3 eye, const visibility::Aabb& eye_region);
    /// The state of a replicated entity whose box is `box`, after prepare().
    [[nodiscard]] EntityState classify(const visibility::Aabb& box) const;

private:
    std::unique_ptr<visibility::RegionVisibility> from_eye_;
    std::unique_ptr<visibility::RegionVisibility> from_region_;
    bool have_region_ = false;
};

} // namespace dsoc::inspect
