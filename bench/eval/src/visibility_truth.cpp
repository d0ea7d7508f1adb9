#include "dsoc/eval/visibility_truth.hpp"

#include "dsoc/eval/parallel.hpp"

#include <algorithm>

namespace dsoc::eval {

void VisibilityTruth::judge(const WorldSim& world, int lookahead, int threads, int client_stride,
                            const RegionEyes& region_eyes) {
    const auto stride = static_cast<std::size_t>(std::max(1, client_stride));
    const WorldFrame& now = world.current();
    entities_ = now.entities.size();
    const std::size_t viewers = world.viewer_count();
    flags_.assign(viewers * entities_, 0);
    parallel_for((viewers + stride - 1) / stride, threads, [&](std::size_t j, int /*worker*/) {
        const std::size_t c = j * stride;
        std::vector<glm::vec3> my_eyes;
        my_eyes.push_back(world.eye(world.ahead(0), c));
        // Every eye, after a respawn too: the world decides a respawn at least
        // `lookahead` ticks ahead (WorldSim), so the policies were told of it.
        for (int k = 1; k <= lookahead; ++k) {
            my_eyes.push_back(world.eye(world.ahead(k), c));
        }
        std::vector<glm::vec3> lattice;
        if (region_eyes) {
            region_eyes(c, lattice);
        }
        std::uint8_t* row = flags_.data() + c * entities_;
        for (std::size_t e = 0; e < entities_; ++e) {
            if (e == c) {
                continue;
            }
            const visibility::Aabb& box = now.entities[e].box;
            if (rays_->box_visible(my_eyes[0], box, grid_)) {
                row[e] = kPresent | kLookahead | kRegion;
                continue;
            }
            for (std::size_t k = 1; k < my_eyes.size(); ++k) {
                if (rays_->box_visible(my_eyes[k], box, grid_)) {
                    row[e] = kLookahead | kRegion;
                    break;
                }
            }
            for (std::size_t k = 0; row[e] == 0 && k < lattice.size(); ++k) {
                if (rays_->box_visible(lattice[k], box, grid_)) {
                    row[e] = kRegion;
                }
            }
        }
    });
}

void VisibilityTruth::ideal_set(std::size_t client, std::vector<std::uint32_t>& out) const {
    out.clear();
    const std::uint8_t* row = flags_.data() + client * entities_;
    for (std::size_t e = 0; e < entities_; ++e) {
        if ((row[e] & kLookahead) != 0) {
            out.push_back(static_cast<std::uint32_t>(e));
        }
    }
}

} // namespace dsoc::eval
