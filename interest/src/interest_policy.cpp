#include "dsoc/interest/interest_policy.hpp"

#include "dsoc/interest/culler_stages.hpp"
#include "dsoc/interest/culling_policy.hpp"

#include <algorithm>
#include <stdexcept>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace dsoc::interest {

bool eye_pvs_rows(const maps::Pvs* pvs, glm::vec3 eye, std::vector<std::int32_t>& clusters,
                  std::vector<std::uint8_t>& rows) {
    if (pvs == nullptr || !pvs->has_visibility() ||
        !pvs->clusters_of(visibility::Aabb{eye, eye}, clusters)) {
        return false;
    }
    pvs->union_of_rows(clusters, rows);
    return true;
}

bool viewer_pvs_rows(const maps::Pvs* pvs, const Viewer& viewer,
                     std::vector<std::int32_t>& clusters, std::vector<std::uint8_t>& rows,
                     std::vector<std::uint8_t>& scratch) {
    if (!eye_pvs_rows(pvs, viewer.eye, clusters, rows)) {
        return false;
    }
    if (!viewer.arrival_eye) {
        return true;
    }
    if (!eye_pvs_rows(pvs, *viewer.arrival_eye, clusters, scratch)) {
        return false;
    }
    for (std::size_t i = 0; i < rows.size() && i < scratch.size(); ++i) {
        rows[i] |= scratch[i];
    }
    return true;
}

void BroadcastPolicy::begin_tick(const WorldView& world, std::uint64_t /*tick*/) {
    ids_.resize(world.entity_count());
    for (std::size_t i = 0; i < ids_.size(); ++i) {
        ids_[i] = world.entity(i).id;
    }
}

void BroadcastPolicy::select(const WorldView& /*world*/, const Viewer& /*viewer*/,
                             std::vector<Interest>& out) {
    out.clear();
    for (const std::uint32_t id : ids_) {
        out.push_back({id, 0});
    }
}

void DistancePolicy::begin_tick(const WorldView& world, std::uint64_t /*tick*/) {
    ids_.resize(world.entity_count());
    boxes_.resize(ids_.size());
    teams_.resize(ids_.size());
    for (std::size_t i = 0; i < ids_.size(); ++i) {
        const EntityView e = world.entity(i);
        ids_[i] = e.id;
        boxes_[i] = e.box;
        teams_[i] = e.team;
    }
}

void DistancePolicy::select(const WorldView& /*world*/, const Viewer& viewer,
                            std::vector<Interest>& out) {
    out.clear();
    for (std::size_t i = 0; i < ids_.size(); ++i) {
        if (visibility::replicated_under(visibility::team_relevance(viewer.team, teams_[i]),
                                         within_radius(boxes_[i], viewer, radius_))) {
            out.push_back({ids_[i], 0});
        }
    }
}

void PvsPolicy::begin_tick(const WorldView& world, std::uint64_t /*tick*/) {
    const std::size_t count = world.entity_count();
    ids_.resize(count);
    always_sent_.resize(count);
    teams_.resize(count);
    cluster_start_.resize(count + 1);
    clusters_.clear();
    const bool vis = pvs_ != nullptr && pvs_->has_visibility();
    for (std::size_t i = 0; i < count; ++i) {
        const EntityView e = world.entity(i);
        ids_[i] = e.id;
        teams_[i] = e.team;
        cluster_start_[i] = static_cast<std::uint32_t>(clusters_.size());
        // Pvs::may_see_clusters()'s answer for a cluster outside the rows: may see.
        const bool always = !vis || !pvs_->clusters_of(e.box, scratch_) ||
                            std::any_of(scratch_.begin(), scratch_.end(), [&](std::int32_t c) {
                                return c < 0 || c >= pvs_->cluster_count();
                            });
        always_sent_[i] = always ? 1 : 0;
        if (!always) {
            clusters_.insert(clusters_.end(), scratch_.begin(), scratch_.end());
        }
    }
    cluster_start_[count] = static_cast<std::uint32_t>(clusters_.size());
}

void PvsPolicy::select(const WorldView& /*world*/, const Viewer& viewer,
                       std::vector<Interest>& out) {
    out.clear();
    // Per-thread scratch: select() runs concurrently for distinct viewers.
    thread_local std::vector<std::int32_t> eye_clusters;
    thread_local std::vector<std::uint8_t> rows;
    thread_local std::vector<std::uint8_t> arrival_rows;
    // Rows hold cluster_count() bits (the map loader rejects shorter ones), and clusters_
    // only clusters below it; the size check is defensive: without it, everything is sent.
    const bool known = viewer_pvs_rows(pvs_.get(), viewer, eye_clusters, rows, arrival_rows) &&
                       rows.size() * 8 >= static_cast<std::size_t>(pvs_->cluster_count());
    const std::uint8_t* const row_bits = rows.data();
    for (std::size_t i = 0; i < ids_.size(); ++i) {
        bool seen = !known || always_sent_[i] != 0;
        for (std::uint32_t k = cluster_start_[i]; !seen && k < cluster_start_[i + 1]; ++k) {
            seen = (row_bits[clusters_[k] >> 3] >> (clusters_[k] & 7) & 1u) != 0;
        }
        if (visibility::replicated_under(visibility::team_relevance(viewer.team, teams_[i]),
                                         seen)) {
            out.push_back({ids_[i], 0});
        }
    }
}

void apply_policy_presets(PolicyKind policy, visibility::DSOCConfig& config) {
    if (policy == PolicyKind::occlusion) { // every entity's current box, every tick
        config.tbvs_enabled = false;
        config.reuse_buffers = false;
        config.full_test_interval = 1;
        config.blocker_hints = false; // no temporal coherence at all
    }
}

void set_culler_stages(CullerKind culler, visibility::RegionCullerConfig& config) {
    config.pyramid = culler != CullerKind::shaft;
    config.shaft = culler != CullerKind::pyramid;
}

int lookahead_ticks(int latency_allowance_ms, int tick_rate) {
    return static_cast<int>((static_cast<long>(latency_allowance_ms) * tick_rate + 999) / 1000);
}

bool use_exact_stages(const PolicySettings& settings,
                      const visibility::CellVisibilityTable& table) {
    if (settings.exact_stages != ExactStages::when_coarse) {
        return settings.exact_stages == ExactStages::always;
    }
    // The bake grows cells by 1.25x steps until the table fits its memory and time
    // budgets: a grown table was made coarse by the map's size, not chosen.
    return table.grid().cell_size > settings.bake_cell_size * 1.01f;
}

std::unique_ptr<InterestPolicy> make_policy(const PolicySettings& settings, const GameWorld& world,
                                            const BakedTableSource& baked_table) {
    switch (settings.policy) {
    case PolicyKind::broadcast:
        return std::make_unique<BroadcastPolicy>();
    case PolicyKind::distance:
        return std::make_unique<DistancePolicy>(settings.distance_radius);
    case PolicyKind::pvs:
        return std::make_unique<PvsPolicy>(world.map().pvs);
    case PolicyKind::dsoc:
    case PolicyKind::occlusion:
        break; // the culling policies, below
    }
    CullerStages stages;
    set_culler_stages(settings.culler, stages.exact_config);
    stages.exact_config.portal_depth = settings.portal_depth;
    if (settings.pvs_stage) { // the map's PVS over the reachable clusters
        stages.pvs = world.map().pvs;
    }
    auto scene = visibility::OccluderScene::build(world.map().occluders);
    if (settings.baked_stage) { // the baked cell table before them (or alone)
        if (!baked_table) {
            throw std::invalid_argument("make_policy: baked_stage without a baked table");
        }
        stages.table = baked_table(*scene);
        stages.exact = use_exact_stages(settings, *stages.table);
    }
    return std::make_unique<CullingPolicy>(
        name_of(settings.policy), settings.dsoc, world.map(), world.move_config(),
        make_culler(std::move(scene), stages), settings.lookahead_ticks);
}

} // namespace dsoc::interest
