#include "dsoc/visibility/occluder_region_visibility.hpp"

#include "dsoc/visibility/occluder_merge.hpp"

namespace dsoc::visibility {

std::shared_ptr<const OccluderScene>
OccluderScene::build(const std::vector<ConvexPolyhedron>& occluders) {
    auto scene = std::make_shared<OccluderScene>();
    for (const auto& o : merge_box_occluders(occluders)) {
        if (!o.is_empty()) {
            scene->world.add(o);
        }
    }
    scene->bsp.build(scene->world);
    scene->grid = std::make_unique<OccluderGrid>(scene->world);
    scene->bvh = std::make_unique<OccluderBvh>(scene->world);
    return scene;
}

} // namespace dsoc::visibility
