#include "dsoc/inspect/trace_source.hpp"

#include <algorithm>

namespace dsoc::inspect {

bool TraceSource::open(const std::string& path, std::string& error) {
    if (!reader_.open(path)) {
        error = reader_.error();
        return false;
    }
    occluders_.clear();
    bounds_ = visibility::Aabb::empty();
    for (const trace::TraceOccluder& o : reader_.header().occluders) {
        visibility::PolyhedronResult result;
        auto poly = visibility::ConvexPolyhedron::from_planes(o.planes, result);
        if (!result.ok()) {
            error = path + ": header occluder " + std::to_string(o.id) +
                    " is not a usable solid (" + visibility::to_string(result.error) + ": " +
                    result.detail + ")";
            return false;
        }
        bounds_.extend(poly.bounds());
        occluders_.push_back(std::move(poly));
    }
    scene_ = visibility::OccluderScene::build(occluders_);
    // No PVS in a trace; both occluder stages, from a point the pyramid is tight.
    classifier_ =
        std::make_unique<ReplicatedClassifier>(scene_, nullptr, visibility::RegionCullerConfig{});
    return true;
}

bool TraceSource::next_view(std::uint64_t min_tick, std::optional<std::uint32_t> client,
                            ClientView& view, std::string& error) {
    error.clear();
    while (reader_.next(tick_)) {
        if (tick_.t < min_tick) {
            continue;
        }
        const auto it =
            std::find_if(tick_.clients.begin(), tick_.clients.end(),
                         [&](const trace::TraceClient& c) { return !client || c.id == *client; });
        if (it == tick_.clients.end()) {
            continue;
        }
        view = ClientView{};
        view.tick = tick_.t;
        view.client = it->id;
        view.eye = it->eye;
        view.viewer_entity = it->entity;
        classifier_->prepare(it->eye, visibility::Aabb::empty());
        std::vector<std::uint32_t> replicated = it->replicated;
        std::sort(replicated.begin(), replicated.end());
        std::vector<trace::TraceEntity> entities = tick_.entities;
        std::sort(entities.begin(), entities.end(),
                  [](const auto& a, const auto& b) { return a.id < b.id; });
        for (const trace::TraceEntity& e : entities) {
            if (it->entity && e.id == *it->entity) {
                view.viewer_box = e.box;
                continue;
            }
            EntityView ev;
            ev.id = e.id;
            ev.box = e.box;
            const auto listed = [&](const std::vector<std::uint32_t>& ids) {
                return std::find(ids.begin(), ids.end(), e.id) != ids.end();
            };
            if (!std::binary_search(replicated.begin(), replicated.end(), e.id)) {
                ev.state = EntityState::not_replicated;
            } else if (listed(it->heard)) {
                ev.state = EntityState::replicated_heard;
            } else if (listed(it->always)) {
                ev.state = EntityState::replicated_rule;
            } else {
                ev.state = classifier_->classify(e.box);
            }
            view.entities.push_back(ev);
        }
        if (view.viewer_entity && view.viewer_box.is_empty()) {
            view.viewer_entity.reset(); // its entity is not in this tick's list
        }
        return true;
    }
    error = reader_.error();
    return false;
}

} // namespace dsoc::inspect
