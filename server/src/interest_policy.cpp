#include "dsoc/server/interest_policy.hpp"

#include "dsoc/maps/pvs_region_visibility.hpp"
#include "dsoc/server/culling_policy.hpp"
#include "dsoc/server/dsoc_settings.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace dsoc::server {

void BroadcastPolicy::select(const GameWorld& world, const Viewer& /*viewer*/,
                             std::vector<Interest>& out) {
    out.clear();
    for (const Entity& e : world.entities()) {
        out.push_back({e.id, 0});
    }
}

void DistancePolicy::select(const GameWorld& world, const Viewer& viewer,
                            std::vector<Interest>& out) {
    out.clear();
    const float r2 = radius_ * radius_;
    for (const Entity& e : world.entities()) {
        // Distance from the eye to the nearest point of the entity's box.
        const visibility::Aabb box = world.box_of(e);
        const glm::vec3 nearest = glm::clamp(viewer.eye, box.min, box.max);
        const glm::vec3 d = nearest - viewer.eye;
        if (glm::dot(d, d) <= r2) {
            out.push_back({e.id, 0});
        }
    }
}

void PvsPolicy::begin_tick(const GameWorld& world, std::uint64_t /*tick*/) {
    const auto& entities = world.entities();
    ids_.resize(entities.size());
    always_sent_.resize(entities.size());
    if (clusters_.size() < entities.size()) {
        clusters_.resize(entities.size());
    }
    const bool vis = pvs_ != nullptr && pvs_->has_visibility();
    for (std::size_t i = 0; i < entities.size(); ++i) {
        ids_[i] = entities[i].id;
        always_sent_[i] = !vis || !pvs_->clusters_of(world.box_of(entities[i]), clusters_[i]);
    }
}

void PvsPolicy::select(const GameWorld& /*world*/, const Viewer& viewer,
                       std::vector<Interest>& out) {
    out.clear();
    // Per-thread scratch: select() runs concurrently for distinct viewers.
    thread_local std::vector<std::int32_t> eye_clusters;
    thread_local std::vector<std::uint8_t> rows;
    const bool known = pvs_ != nullptr && pvs_->has_visibility() &&
                       pvs_->clusters_of(visibility::Aabb{viewer.eye, viewer.eye}, eye_clusters);
    if (known) {
        pvs_->union_of_rows(eye_clusters, rows);
    }
    for (std::size_t i = 0; i < ids_.size(); ++i) {
        if (!known || always_sent_[i] || pvs_->may_see_clusters(rows, clusters_[i])) {
            out.push_back({ids_[i], 0});
        }
    }
}

std::unique_ptr<InterestPolicy> make_policy(const ServerConfig& config, const GameWorld& world) {
    if (config.policy == "broadcast") {
        return std::make_unique<BroadcastPolicy>();
    }
    if (config.policy == "distance") {
        return std::make_unique<DistancePolicy>(config.distance_radius);
    }
    if (config.policy == "pvs") {
        return std::make_unique<PvsPolicy>(world.map().pvs);
    }
    // Flat keys, the occlusion policy's presets, then the [dsoc] table (dsoc_settings.hpp).
    const visibility::DSOCConfig dsoc = dsoc_config(config);
    visibility::RegionCullerConfig culler;
    culler.pyramid = config.culler != "shaft";
    culler.shaft = config.culler != "pyramid";
    culler.portal_depth = config.portal_depth;
    auto scene = visibility::OccluderScene::build(world.map().occluders);
    auto make_culler = visibility::occluder_region_visibility(scene, culler);
    if (config.pvs_stage) { // the map's PVS over the reachable clusters first
        make_culler = maps::with_pvs_stage(world.map().pvs, std::move(make_culler));
    }
    return std::make_unique<CullingPolicy>(config.policy, dsoc, world, std::move(make_culler),
                                           lookahead_ticks(config));
}

} // namespace dsoc::server
