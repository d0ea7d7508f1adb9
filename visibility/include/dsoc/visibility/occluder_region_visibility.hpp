#pragma once
// The standard RegionVisibility: a from-region z-pyramid (RegionOcclusionBuffer)
// over an occluder world, occluders taken near-to-far from its BSP tree.

#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/occluder_bvh.hpp"
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
    /// The shaft stage's check for a clear centre segment (built by build()).
    std::unique_ptr<OccluderBvh> bvh;

    /// Merges axis-aligned boxes that tile larger boxes (merge_box_occluders: the same
    /// solid, fewer seams), adds every non-empty polyhedron and builds the BSP.
    static std::shared_ptr<const OccluderScene>
    build(const std::vector<ConvexPolyhedron>& occluders);
};

/// Which stages a region culler runs; both are conservative.
struct RegionCullerConfig {
    /// The extended-projection z-pyramid: a build per region (its cost is the build),
    /// then a few texel reads per box; fuses occluders per texel; loses much to parallax
    /// when the region is wide compared with the occluders' distance.
    bool pyramid = true;
    /// The exact single-occluder shaft test: no build, but the dearest per box that
    /// reaches it (docs/region-visibility.md has the figures).
    bool shaft = true;
    /// Within the shaft stage, occluder fusion across cut planes through the walls
    /// the centre segment crosses (cut_plane_fusion.hpp), for boxes no single
    /// occluder hides.
    bool fusion = true;
    /// Within fusion, levels of portal tests (shaft_occlusion.hpp): the open parts a
    /// cut plane leaves are tested in turn. 0 turns them off. [Limit: 0..4]
    int portal_depth = ShaftOcclusion::kDefaultPortalDepth;
    RegionOcclusionBufferConfig buffer;
};

/// Region culler over an occluder scene: the z-pyramid first (when enabled), then the
/// shaft test for the boxes it could not prove hidden. One instance per client:
/// test_box() uses per-instance scratch, so one thread at a time per instance.
class OccluderRegionVisibility final : public RegionVisibility {
public:
    OccluderRegionVisibility(std::shared_ptr<const OccluderScene> scene,
                             const RegionCullerConfig& config = {})
        : scene_(std::move(scene)), config_(config),
          buffer_(config.pyramid ? std::make_unique<RegionOcclusionBuffer>(config.buffer)
                                 : nullptr) {}

    void build(const Aabb& region) override {
        region_ = region;
        if (buffer_) {
            buffer_->build(region, scene_->world, scene_->bsp);
        }
    }
    [[nodiscard]] Visibility test_box(const Aabb& box) const override {
        return test_with_hint(box, nullptr);
    }
    /// test_box() trying first the occluder that hid the box last time (ShaftOcclusion).
    [[nodiscard]] Visibility test_box_hinted(const Aabb& box, std::uint32_t& hint) const override {
        return test_with_hint(box, &hint);
    }
    /// The z-pyramid alone; without it, no test at all (`visible`, which is always
    /// allowed): an entity visible last tick stays replicated until its next full test.
    [[nodiscard]] Visibility test_box_quick(const Aabb& box) const override {
        return buffer_ ? buffer_->test_box(box) : Visibility::visible;
    }
    /// The z-pyramid; nullptr without the pyramid stage (no memory is taken for it:
    /// about 130 KB per culler at the default 64 x 64 faces).
    [[nodiscard]] const RegionOcclusionBuffer* buffer() const { return buffer_.get(); }

private:
    /// The z-pyramid, then the shaft stage with `hint` (nullptr: none).
    [[nodiscard]] Visibility test_with_hint(const Aabb& box, std::uint32_t* hint) const {
        if (buffer_ && buffer_->test_box(box) == Visibility::occluded) {
            return Visibility::occluded;
        }
        if (!config_.shaft || scene_->grid == nullptr) {
            return Visibility::visible;
        }
        return ShaftOcclusion(scene_->world, *scene_->grid, config_.fusion, config_.portal_depth,
                              scene_->bvh.get())
            .test(region_, box, scratch_, hint);
    }

    std::shared_ptr<const OccluderScene> scene_;
    RegionCullerConfig config_;
    std::unique_ptr<RegionOcclusionBuffer> buffer_;
    Aabb region_;
    mutable ShaftOcclusion::Scratch scratch_;
};

/// A factory for InterestManager: one OccluderRegionVisibility per client over `scene`.
[[nodiscard]] inline RegionVisibilityFactory
occluder_region_visibility(std::shared_ptr<const OccluderScene> scene,
                           const RegionCullerConfig& config = {}) {
    return [scene = std::move(scene), config] {
        return std::make_unique<OccluderRegionVisibility>(scene, config);
    };
}

} // namespace dsoc::visibility
