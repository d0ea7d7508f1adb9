#pragma once
// The occlusion-aware policies: "dsoc" (TBVs, region reuse, latency-safe) and
// "occlusion" (the same culler, every entity's current box tested every tick, no
// TBVs). Both wrap dsoc::visibility::InterestManager.

#include "dsoc/server/interest_policy.hpp"
#include "dsoc/sim/reach_clipper.hpp"
#include "dsoc/visibility/interest_manager.hpp"

#include <memory>
#include <string_view>
#include <vector>

namespace dsoc::server {

class CullingPolicy final : public InterestPolicy {
public:
    /// `name` is reported by name(); `config` must have passed validate();
    /// `lookahead_ticks` is the client latency allowance in ticks.
    CullingPolicy(std::string_view name, const visibility::DSOCConfig& config,
                  const GameWorld& world, visibility::RegionVisibilityFactory make_visibility,
                  int lookahead_ticks);

    [[nodiscard]] std::string_view name() const override { return name_; }
    void begin_tick(const GameWorld& world, std::uint64_t tick) override;
    void select(const GameWorld& world, const Viewer& viewer,
                std::vector<std::uint32_t>& out) override;
    void add_viewer(std::uint32_t client_id, std::uint32_t entity_id) override;
    void remove_viewer(std::uint32_t client_id) override;

    [[nodiscard]] const visibility::InterestManager& manager() const { return manager_; }

private:
    void sync_entities(const GameWorld& world);

    std::string name_;
    std::shared_ptr<const sim::ReachClipper> clipper_;
    visibility::InterestManager manager_;
    visibility::EntityDesc entity_desc_;
    visibility::ClientDesc client_desc_;
    std::vector<std::uint32_t> known_entities_; // increasing
    std::vector<std::uint32_t> scratch_;
};

} // namespace dsoc::server
