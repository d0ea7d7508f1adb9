#include "dsoc/interest/culler_stages.hpp"

#include "dsoc/maps/pvs_region_visibility.hpp"
#include "dsoc/visibility/baked_region_visibility.hpp"

#include <utility>

namespace dsoc::interest {

visibility::RegionVisibilityFactory
make_culler(std::shared_ptr<const visibility::OccluderScene> scene, const CullerStages& stages) {
    visibility::RegionVisibilityFactory exact;
    if (stages.exact || stages.table == nullptr) {
        exact = maps::with_pvs_stage(stages.pvs, visibility::occluder_region_visibility(
                                                     std::move(scene), stages.exact_config));
    }
    return visibility::with_baked_stage(stages.table, std::move(exact));
}

} // namespace dsoc::interest
