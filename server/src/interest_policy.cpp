#include "dsoc/server/interest_policy.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace dsoc::server {

void BroadcastPolicy::select(const GameWorld& world, const Viewer& /*viewer*/,
                             std::vector<std::uint32_t>& out) {
    out.clear();
    for (const Entity& e : world.entities()) {
        out.push_back(e.id);
    }
}

void DistancePolicy::select(const GameWorld& world, const Viewer& viewer,
                            std::vector<std::uint32_t>& out) {
    out.clear();
    const float r2 = radius_ * radius_;
    for (const Entity& e : world.entities()) {
        // Distance from the eye to the nearest point of the entity's box.
        const glm::vec3 nearest =
            glm::clamp(viewer.eye, e.position - e.half_extents, e.position + e.half_extents);
        const glm::vec3 d = nearest - viewer.eye;
        if (glm::dot(d, d) <= r2) {
            out.push_back(e.id);
        }
    }
}

std::unique_ptr<InterestPolicy> make_policy(const ServerConfig& config) {
    if (config.policy == "broadcast") {
        return std::make_unique<BroadcastPolicy>();
    }
    return std::make_unique<DistancePolicy>(config.distance_radius);
}

} // namespace dsoc::server
