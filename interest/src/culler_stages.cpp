#include "dsoc/interest/culler_stages.hpp"

#include "dsoc/maps/pvs_region_visibility.hpp"
#include "dsoc/visibility/baked_region_visibility.hpp"

#include <utility>

namespace dsoc::interest {

visibility::RegionVisibilityFactory
make_culler(std::shared_ptr<const visibility::OccluderScene> scene, const CullerStages& stages) {
    // Without `exact` the table answers alone wherever it covers the region and the box;
    // the exact stages answer only what it does not cover (built per client when first
    // needed, and kept). There they run without the z-pyramid when the shaft test is on:
    // its raster pass per region and its buffer per client (about 130 KB, so 65 MB for
    // 500 clients) would buy little for the few regions the table does not cover.
    visibility::RegionCullerConfig exact_config = stages.exact_config;
    if (!stages.exact && stages.table != nullptr && exact_config.shaft) {
        exact_config.pyramid = false;
    }
    auto exact = maps::with_pvs_stage(
        stages.pvs, visibility::occluder_region_visibility(std::move(scene), exact_config));
    using NextFor = visibility::BakedRegionVisibility::NextFor;
    return visibility::with_baked_stage(stages.table, std::move(exact),
                                        stages.exact ? NextFor::after_table
                                                     : NextFor::where_uncovered);
}

} // namespace dsoc::interest
