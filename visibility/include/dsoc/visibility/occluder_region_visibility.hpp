#pragma once
// The standard RegionVisibility: a from-region z-pyramid (RegionOcclusionBuffer)
// over an occluder world, occluders taken near-to-far from its BSP tree.

#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/occluder_world.hpp"
#include "dsoc/visibility/region_occlusion_buffer.hpp"
#include "dsoc/visibility/region_visibility.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"

#include <memory>

namespace dsoc::visibility {

/// An occluder world with its BSP tree, built once and shared (read-only) by every
/// client's culler.
struct OccluderScene {
    OccluderWorld world;
    BspTree bsp;
    /// Candidate lookup for the shaft stage (built by build()).
    std::unique_ptr<OccluderGrid> grid;

    /// Merges axis-aligned boxes that tile larger boxes (merge_box_occluders: the same
    /// solid, fewer seams), adds every non-empty polyhedron and builds the BSP.
    static std::shared_ptr<const OccluderScene>
    build(const std::vector<ConvexPolyhedron>& occluders);
};

/// Two stages, both conservative: the extended-projection z-pyramid (fast, fuses
/// occluders per texel), then for boxes it could not prove hidden, the exact
/// single-occluder shaft test (slower, no fusion, no parallax loss). One instance per
/// client: test_box() uses per-instance scratch, so one thread at a time per instance.
class OccluderRegionVisibility final : public RegionVisibility {
public:
    OccluderRegionVisibility(std::shared_ptr<const OccluderScene> scene,
                             const RegionOcclusionBufferConfig& config, bool shaft_stage = true)
        : scene_(std::move(scene)), buffer_(config), shaft_stage_(shaft_stage) {}

    void build(const Aabb& region) override {
        region_ = region;
        buffer_.build(region, scene_->world, scene_->bsp);
    }
    [[nodiscard]] Visibility test_box(const Aabb& box) const override {
        if (buffer_.test_box(box) == Visibility::occluded) {
            return Visibility::occluded;
        }
        if (!shaft_stage_ || scene_->grid == nullptr) {
            return Visibility::visible;
        }
        return ShaftOcclusion(scene_->world, *scene_->grid).test(region_, box, scratch_);
    }
    /// The z-pyramid stage alone.
    [[nodiscard]] Visibility test_box_quick(const Aabb& box) const override {
        return buffer_.test_box(box);
    }
    [[nodiscard]] const RegionOcclusionBuffer& buffer() const { return buffer_; }

private:
    std::shared_ptr<const OccluderScene> scene_;
    RegionOcclusionBuffer buffer_;
    bool shaft_stage_;
    Aabb region_;
    mutable OccluderGrid::Scratch scratch_;
};

/// A factory for InterestManager: one OccluderRegionVisibility per client over `scene`.
[[nodiscard]] inline RegionVisibilityFactory
occluder_region_visibility(std::shared_ptr<const OccluderScene> scene,
                           const RegionOcclusionBufferConfig& config = {},
                           bool shaft_stage = true) {
    return [scene = std::move(scene), config, shaft_stage] {
        return std::make_unique<OccluderRegionVisibility>(scene, config, shaft_stage);
    };
}

} // namespace dsoc::visibility
