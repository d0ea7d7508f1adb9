#pragma once
// The occlusion-aware policies: "dsoc" (temporal coherence, latency-safe; TBVs when
// DSOCConfig::tbvs_enabled) and "occlusion" (the same culler, every entity's current
// box fully tested every tick). Both wrap dsoc::visibility::InterestManager: begin_tick() is its
// serial begin_update(); select() runs the viewer's update_client() and reads its decisions, so the
// per-client culling of a tick runs wherever select() is called (in parallel on the server's worker
// pool). The manager's network level-of-detail hint (update_interval 1/2/4) becomes Interest::tier
// 0/1/2.
//
// A viewer whose respawn is pending (EntityView::arrival_eye) is also given a
// spectator client of the manager at its arrival eye, whose reachable region covers
// every eye the viewer can have from its arrival to the end of its latency allowance;
// select() answers the union of the two clients' sets.

#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/interest/walking_interest.hpp"

#include <map>
#include <memory>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace dsoc::interest {

class CullingPolicy final : public InterestPolicy {
public:
    /// `name` is reported by name(); `config` must have passed validate(); `map` (which
    /// must outlive the policy) and `move` are the world's, whose entities all walk by
    /// `move`; `lookahead_ticks` is the client latency allowance in ticks.
    CullingPolicy(std::string_view name, const visibility::DSOCConfig& config, const maps::Map& map,
                  const sim::MoveConfig& move, visibility::RegionVisibilityFactory make_visibility,
                  int lookahead_ticks);

    [[nodiscard]] std::string_view name() const override { return name_; }
    void begin_tick(const WorldView& world, std::uint64_t tick) override;
    void select(const WorldView& world, const Viewer& viewer, std::vector<Interest>& out) override;
    /// The culler's prepared stage alone (visibility::UpdateEffort::cheapest).
    void select_cheapest(const WorldView& world, const Viewer& viewer,
                         std::vector<Interest>& out) override;
    /// `client_id` < kArrivalClientBit (the ids above are the arrival spectators').
    void add_viewer(std::uint32_t client_id, std::uint32_t entity_id) override;
    void remove_viewer(std::uint32_t client_id) override;
    [[nodiscard]] std::size_t tbvs_alive() const override;

    [[nodiscard]] const visibility::InterestManager& manager() const { return interest_.manager(); }

    /// The manager's client id of a viewer's arrival spectator: client_id | this bit.
    static constexpr std::uint32_t kArrivalClientBit = 0x80000000u;

private:
    void sync_entities(const WorldView& world);
    /// Adds, moves and removes the arrival spectators (after sync_entities()).
    void sync_arrivals();
    void rebuild_client_index();
    void select_with(const Viewer& viewer, visibility::UpdateEffort effort,
                     std::vector<Interest>& out);

    [[nodiscard]] visibility::InterestManager& manager() { return interest_.manager(); }

    std::string name_;
    WalkingInterest interest_;
    std::vector<std::uint32_t> known_entities_; // increasing
    std::vector<std::uint32_t> scratch_;
    std::vector<visibility::TeamId> entity_teams_; // by known_entities_ index, this tick
    /// This tick's pending arrivals: (entity id, arrival eye), increasing ids.
    std::vector<std::pair<std::uint32_t, glm::vec3>> arrivals_;
    /// Client id -> the entity it views from, and whether it has an arrival spectator.
    struct ViewerEntry {
        std::uint32_t entity_id = 0;
        bool arriving = false;
    };
    std::map<std::uint32_t, ViewerEntry> viewers_;
    /// Client id -> the manager's client index, rebuilt by begin_tick(); read-only
    /// while select() runs.
    std::unordered_map<std::uint32_t, std::size_t> client_index_;
};

} // namespace dsoc::interest
