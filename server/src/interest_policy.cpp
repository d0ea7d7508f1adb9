#include "dsoc/server/interest_policy.hpp"

#include "dsoc/interest/culler_stages.hpp"
#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/server/culling_policy.hpp"
#include "dsoc/server/dsoc_settings.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <stdexcept>

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

std::shared_ptr<const visibility::CellVisibilityTable>
baked_table(const ServerConfig& config, const GameWorld& world,
            const visibility::OccluderScene& scene) {
    maps::BakeRequest request;
    request.config.cell_size = config.bake_cell_size;
    request.dir = config.bake_dir;
    const std::string& name = world.map().name;
    auto baked = maps::load_or_bake(world.map(), scene, request, [&](double f, double seconds) {
        const double eta = f > 0.0 ? seconds * (1.0 - f) / f : 0.0;
        std::fprintf(stderr, "\rbaking the cell visibility of %s: %5.1f%%, %.0f s, ETA %.0f s ",
                     name.c_str(), 100.0 * f, seconds, eta);
        if (f >= 1.0) {
            std::fprintf(stderr, "\n");
        }
    });
    if (!baked) {
        throw std::runtime_error("baked stage: " + baked.error().message());
    }
    if (!baked->cache_problem.empty()) {
        spdlog::warn("baked stage: cached table refused: {}", baked->cache_problem);
    }
    if (!baked->write_problem.empty()) {
        spdlog::warn("baked stage: table not saved: {}", baked->write_problem);
    }
    spdlog::info("baked stage: {} {} ({} open cells of {:.0f} units, {:.1f} MiB)",
                 baked->from_cache ? "loaded" : "baked and saved", baked->file.string(),
                 baked->table->open_count(), static_cast<double>(baked->table->grid().cell_size),
                 static_cast<double>(baked->table->memory_bytes()) / (1 << 20));
    return baked->table;
}

bool use_exact_stages(const ServerConfig& config, const visibility::CellVisibilityTable& table) {
    if (config.exact_stages != "auto") {
        return config.exact_stages == "true";
    }
    // The bake grows cells by 1.25x steps until the table fits its budget: a grown
    // table was made coarse by the map's size, not chosen.
    return table.grid().cell_size > config.bake_cell_size * 1.01f;
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
    interest::CullerStages stages;
    stages.exact_config.pyramid = config.culler != "shaft";
    stages.exact_config.shaft = config.culler != "pyramid";
    stages.exact_config.portal_depth = config.portal_depth;
    if (config.pvs_stage) { // the map's PVS over the reachable clusters
        stages.pvs = world.map().pvs;
    }
    auto scene = visibility::OccluderScene::build(world.map().occluders);
    if (config.baked_stage) { // the baked cell table before them (or alone)
        stages.table = baked_table(config, world, *scene);
        stages.exact = use_exact_stages(config, *stages.table);
        spdlog::info("baked stage: {} (exact_stages = {})",
                     stages.exact ? "the table, then the exact stages" : "the table alone",
                     config.exact_stages);
    }
    return std::make_unique<CullingPolicy>(config.policy, dsoc, world,
                                           interest::make_culler(std::move(scene), stages),
                                           lookahead_ticks(config));
}

} // namespace dsoc::server
