#pragma once
// The map's PVS as the first stage of a region culler (docs/latency-safety.md
// §3): the union of the PVS rows of every cluster the client's eye region touches is
// conservative for the whole region, so a box none of whose clusters is in it is
// hidden from every eye of the region. Cheap and coarse; boxes it passes go to the
// next stage.

#include "dsoc/maps/pvs.hpp"
#include "dsoc/visibility/region_visibility.hpp"

#include <memory>
#include <vector>

namespace dsoc::maps {

class PvsRegionVisibility final : public visibility::RegionVisibility {
public:
    /// `next` answers the boxes the PVS passes; `pvs` must outlive this.
    PvsRegionVisibility(std::shared_ptr<const Pvs> pvs,
                        std::unique_ptr<visibility::RegionVisibility> next)
        : pvs_(std::move(pvs)), next_(std::move(next)) {}

    void build(const visibility::Aabb& region) override {
        active_ = pvs_->has_visibility() && pvs_->clusters_of(region, scratch_);
        if (active_) {
            pvs_->union_of_rows(scratch_, visible_clusters_);
        }
        next_->build(region);
    }
    [[nodiscard]] visibility::Visibility test_box(const visibility::Aabb& box) const override {
        return hides(box) ? visibility::Visibility::occluded : next_->test_box(box);
    }
    [[nodiscard]] visibility::Visibility
    test_box_quick(const visibility::Aabb& box) const override {
        return hides(box) ? visibility::Visibility::occluded : next_->test_box_quick(box);
    }

    // Prepared boxes carry their clusters, so the PVS stage costs a few bit tests.
    [[nodiscard]] bool has_prepared_stage() const override { return pvs_->has_visibility(); }
    void prepare(const visibility::Aabb& box, visibility::PreparedBox& out) const override {
        out.box = box;
        out.prepared = pvs_->has_visibility() && pvs_->clusters_of(box, out.keys);
    }
    [[nodiscard]] visibility::Visibility
    test_prepared(const visibility::PreparedBox& p) const override {
        if (!p.prepared) {
            return test_box(p.box);
        }
        return hides(p) ? visibility::Visibility::occluded : next_->test_box(p.box);
    }
    [[nodiscard]] visibility::Visibility
    test_prepared_quick(const visibility::PreparedBox& p) const override {
        if (!p.prepared) {
            return test_box_quick(p.box);
        }
        return hides(p) ? visibility::Visibility::occluded : next_->test_box_quick(p.box);
    }
    [[nodiscard]] visibility::Visibility test_box_hinted(const visibility::Aabb& box,
                                                         std::uint32_t& hint) const override {
        return hides(box) ? visibility::Visibility::occluded : next_->test_box_hinted(box, hint);
    }
    [[nodiscard]] visibility::Visibility test_prepared_hinted(const visibility::PreparedBox& p,
                                                              std::uint32_t& hint) const override {
        if (!p.prepared) {
            return test_box_hinted(p.box, hint);
        }
        return hides(p) ? visibility::Visibility::occluded : next_->test_box_hinted(p.box, hint);
    }
    /// The PVS alone: `visible` whenever the PVS passes the box (the next stage is skipped).
    [[nodiscard]] visibility::Visibility
    test_prepared_coarse(const visibility::PreparedBox& p) const override {
        if (!p.prepared || !active_) {
            return test_prepared(p);
        }
        return hides(p) ? visibility::Visibility::occluded : visibility::Visibility::visible;
    }

private:
    /// Whether no cluster `box` touches is in the region's PVS rows (hidden from every
    /// eye of the region); false before build() found the region's clusters.
    [[nodiscard]] bool hides(const visibility::Aabb& box) const {
        return active_ && !pvs_->may_see(visible_clusters_, box, scratch_);
    }
    /// The same for a prepared box (p.prepared: its clusters are p.keys).
    [[nodiscard]] bool hides(const visibility::PreparedBox& p) const {
        return active_ && !pvs_->may_see_clusters(visible_clusters_, p.keys);
    }

    std::shared_ptr<const Pvs> pvs_;
    std::unique_ptr<visibility::RegionVisibility> next_;
    bool active_ = false;
    std::vector<std::uint8_t> visible_clusters_;
    mutable std::vector<std::int32_t> scratch_;
};

/// Wraps every culler `make_next` makes with the PVS stage; returns `make_next` itself
/// when `pvs` is null or the map has no vis data.
[[nodiscard]] inline visibility::RegionVisibilityFactory
with_pvs_stage(std::shared_ptr<const Pvs> pvs, visibility::RegionVisibilityFactory make_next) {
    if (pvs == nullptr || !pvs->has_visibility()) {
        return make_next;
    }
    return [pvs = std::move(pvs), make_next = std::move(make_next)] {
        return std::make_unique<PvsRegionVisibility>(pvs, make_next());
    };
}

} // namespace dsoc::maps
