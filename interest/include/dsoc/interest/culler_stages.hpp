#pragma once
// The region culler's stages, first to last: the map's baked cell table, the map's
// PVS, then the exact occluder tests (shaft, fusion across cut planes, portals). Each
// stage passes on only what it cannot prove hidden; every stage is conservative on its
// own, so any selection of them is (docs/region-visibility.md, docs/baked-visibility.md).

#include "dsoc/maps/pvs.hpp"
#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"
#include "dsoc/visibility/region_visibility.hpp"

#include <memory>

namespace dsoc::interest {

struct CullerStages {
    /// The map's baked cell visibility table; null: no table.
    std::shared_ptr<const visibility::CellVisibilityTable> table;
    /// The map's PVS over every cluster a region touches; null (or a map without vis
    /// data): no PVS stage.
    std::shared_ptr<const maps::Pvs> pvs;
    /// false: the table alone wherever it covers the region and the box (the PVS and
    /// the exact tests answer only what it does not cover). Needs a table.
    bool exact = true;
    /// The exact occluder tests' settings (shaft, pyramid, fusion, portal depth).
    visibility::RegionCullerConfig exact_config;
};

/// A factory of per-client cullers running `stages` over `scene`'s occluders.
[[nodiscard]] visibility::RegionVisibilityFactory
make_culler(std::shared_ptr<const visibility::OccluderScene> scene, const CullerStages& stages);

} // namespace dsoc::interest
