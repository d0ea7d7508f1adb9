#pragma once
// Ground truth for one tick from the ray oracle: for every (client, entity) pair,
// whether the entity's box at tick t is visible from the client's eye at t (the
// present eye), and whether it is visible from any of the eyes the client really has
// at t .. t + lookahead (the latency allowance of replication-trace.md). Eyes after a
// respawn of the viewer count too: the world decides a respawn `lookahead` ticks
// before it puts the viewer at its spawn point (WorldSim), and tells the policies
// where (interest::Viewer::arrival_eye), so a respawn is no excuse for pop-in.

#include "dsoc/eval/ray_oracle.hpp"
#include "dsoc/eval/world_sim.hpp"

#include <cstdint>
#include <functional>
#include <vector>

namespace dsoc::eval {

class VisibilityTruth {
public:
    static constexpr std::uint8_t kPresent = 1;   ///< visible from the eye at t
    static constexpr std::uint8_t kLookahead = 2; ///< visible from some eye at t .. t + K
    /// Visible from some eye of the client's whole reachable eye region (a lattice of
    /// eyes in it, plus the real ones): what a conservative policy that covers that
    /// region must send at least. Set only when judge() is given region eyes.
    static constexpr std::uint8_t kRegion = 4;

    /// Extra eyes for client `c` (e.g. a lattice over its reachable eye region).
    using RegionEyes = std::function<void(std::size_t c, std::vector<glm::vec3>& eyes)>;

    /// `grid`: samples per box face side (>= 2).
    VisibilityTruth(const RayOracle& rays, int grid) : rays_(&rays), grid_(grid) {}

    /// Judges the tick world.current() with eyes world.ahead(0 .. lookahead), for the
    /// clients c with c % client_stride == 0 (the others' flags are 0). Runs on
    /// `threads` threads.
    void judge(const WorldSim& world, int lookahead, int threads, int client_stride = 1,
               const RegionEyes& region_eyes = {});

    /// Flags of (client, entity) after judge(); the client's own entity is 0.
    [[nodiscard]] std::uint8_t at(std::size_t client, std::size_t entity) const {
        return flags_[client * entities_ + entity];
    }
    /// Entities visible within the allowance, increasing: the oracle's ideal set.
    void ideal_set(std::size_t client, std::vector<std::uint32_t>& out) const;

private:
    const RayOracle* rays_;
    int grid_;
    std::size_t entities_ = 0;
    std::vector<std::uint8_t> flags_;
};

} // namespace dsoc::eval
