#include "dsoc/interest/culler_stages.hpp"

#include "dsoc/maps/pvs_region_visibility.hpp"
#include "dsoc/visibility/baked_region_visibility.hpp"

#include <utility>

namespace dsoc::interest {

visibility::RegionVisibilityFactory
make_culler(std::shared_ptr<const visibility::OccluderScene> scene, const CullerStages& stages) {
    // Without `exact` the table answers alone wherever it covers the region and the box;
    // the exact stages answer only what it does not cover (built when first needed).
    auto exact = maps::with_pvs_stage(
        stages.pvs, visibility::occluder_region_visibility(std::move(scene), stages.exact_config));
    using NextFor = visibility::BakedRegionVisibility::NextFor;
    return visibility::with_baked_stage(stages.table, std::move(exact),
                                        stages.exact ? NextFor::after_table
                                                     : NextFor::where_uncovered);
}

} // namespace dsoc::interest
