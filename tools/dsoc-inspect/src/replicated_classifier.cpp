#include "dsoc/inspect/replicated_classifier.hpp"

#include "dsoc/maps/pvs_region_visibility.hpp"

namespace dsoc::inspect {

ReplicatedClassifier::ReplicatedClassifier(std::shared_ptr<const visibility::OccluderScene> scene,
                                           std::shared_ptr<const maps::Pvs> pvs,
                                           const visibility::RegionCullerConfig& culler) {
    const auto make =
        maps::with_pvs_stage(std::move(pvs), visibility::occluder_region_visibility(scene, culler));
    from_eye_ = make();
    from_region_ = make();
}

void ReplicatedClassifier::prepare(glm::vec3 eye, const visibility::Aabb& eye_region) {
    from_eye_->build(visibility::Aabb{eye, eye});
    have_region_ = !eye_region.is_empty();
    if (have_region_) {
        from_region_->build(eye_region);
    }
}

EntityState ReplicatedClassifier::classify(const visibility::Aabb& box) const {
    if (from_eye_->test_box(box) == visibility::Visibility::visible) {
        return EntityState::replicated_visible;
    }
    if (have_region_ && from_region_->test_box(box) == visibility::Visibility::occluded) {
        return EntityState::replicated_held;
    }
    return EntityState::replicated_lookahead;
}

} // namespace dsoc::inspect
