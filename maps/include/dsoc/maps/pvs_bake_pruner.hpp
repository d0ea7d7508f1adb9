#pragma once
// The map compiler's PVS as the bake's cheap first proof (cell_bake.hpp): two boxes
// are apart when no cluster of one is in the PVS of any cluster of the other. What
// the PVS promises (pvs.hpp) is what this promises.

#include "dsoc/maps/pvs.hpp"
#include "dsoc/visibility/cell_bake.hpp"

#include <memory>

namespace dsoc::maps {

class PvsBakePruner final : public visibility::BakePruner {
public:
    /// `pvs` must have visibility (has_visibility()).
    explicit PvsBakePruner(std::shared_ptr<const Pvs> pvs) : pvs_(std::move(pvs)) {}

    /// A box that surely touches no clustered leaf is in solid or outside the map.
    [[nodiscard]] bool empty_space(const visibility::Aabb& box) const override {
        return pvs_->touches_no_cluster(box);
    }
    void keys(const visibility::Aabb& box, std::vector<std::int32_t>& out) const override {
        if (!pvs_->clusters_of(box, out)) {
            out.clear(); // touches no clustered leaf: nothing known
        }
    }
    [[nodiscard]] bool hidden(std::span<const std::int32_t> a,
                              std::span<const std::int32_t> b) const override {
        if (a.empty() || b.empty()) {
            return false;
        }
        for (const std::int32_t from : a) {
            for (const std::int32_t to : b) {
                // One way: the loaded PVS is symmetric (pvs.hpp), and the bake clears
                // both bits of the pair.
                if (pvs_->cluster_visible(from, to)) {
                    return false;
                }
            }
        }
        return true;
    }

private:
    std::shared_ptr<const Pvs> pvs_;
};

} // namespace dsoc::maps
