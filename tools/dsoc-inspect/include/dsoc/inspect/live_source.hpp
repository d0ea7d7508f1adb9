#pragma once
// The live input of dsoc-inspect: the server's own world (dsoc::interest::GameWorld:
// wandering bots, Quake 3 movement) and its own culling policy
// (dsoc::interest::make_policy: "dsoc" or "occlusion"), run in-process tick by tick,
// with one client viewing from one of the bots. Deterministic for a seed.
//
// Only that one client is added to the interest manager: a client's decisions
// depend on its own state and the shared entities alone, so the picture is what the
// same client would get among any number of others.

#include "dsoc/inspect/client_view.hpp"
#include "dsoc/inspect/replicated_classifier.hpp"
#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/hearing.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <memory>
#include <string>
#include <vector>

namespace dsoc::interest {
class CullingPolicy;
}

namespace dsoc::inspect {

struct LiveOptions {
    /// dsoc (the server's defaults) or occlusion (every box fully tested every tick).
    interest::PolicyKind policy = interest::PolicyKind::dsoc;
    /// dsoc with the paper's TBVs (DSOCConfig::tbvs_enabled; off by default; dsoc only), drawn as
    /// outlines around the entities they hide.
    bool tbvs = false;
    /// Wandering entities (arena-64 has 64 viewers + 512 bots = 576). [Limit: 1..100000]
    int bots = 576;
    /// [Units: Hz] [Limit: 1..240]
    int tick_rate = 30;
    /// Round trip + interpolation the server covers. [Units: ms] [Limit: 0..2000]
    int latency_allowance_ms = 150;
    /// Culler stages: shaft (the server's default), pyramid or both.
    interest::CullerKind culler = interest::CullerKind::shaft;
    std::uint64_t seed = 1;
    /// The bot the inspected client views from. [Limit: 1..bots]
    std::uint32_t viewer_entity = 1;
};

/// Every problem with the options, each naming the option; empty when usable.
[[nodiscard]] std::vector<std::string> validate(const LiveOptions& options);

class LiveSimulation {
public:
    /// `map` needs spawn points. Throws std::invalid_argument with every problem of
    /// validate(options) when they are not usable.
    LiveSimulation(std::shared_ptr<const maps::Map> map, const LiveOptions& options);
    ~LiveSimulation();
    LiveSimulation(const LiveSimulation&) = delete;
    LiveSimulation& operator=(const LiveSimulation&) = delete;

    /// Moves every entity one tick and runs the policy's decision for the client.
    void advance();
    /// Ticks advanced so far (the view's tick).
    [[nodiscard]] std::uint64_t tick() const { return tick_; }
    /// The client's view after the last advance(): eye, reachable eye region, and
    /// every other entity's state (the manager's pair state, replicated ones split
    /// by ReplicatedClassifier) with its TBV box.
    [[nodiscard]] ClientView view();
    /// The occluders the culling uses (shared with the pyramid dump).
    [[nodiscard]] const std::shared_ptr<const visibility::OccluderScene>& scene() const {
        return scene_;
    }

    static constexpr std::uint32_t kClientId = 1;

private:
    std::shared_ptr<const maps::Map> map_;
    LiveOptions options_;
    std::unique_ptr<interest::GameWorld> world_;
    std::unique_ptr<interest::InterestPolicy> policy_;
    const interest::CullingPolicy* culling_ = nullptr; ///< policy_ itself
    std::shared_ptr<const visibility::OccluderScene> scene_;
    std::unique_ptr<ReplicatedClassifier> classifier_;
    interest::Hearing hearing_;
    std::vector<std::uint32_t> heard_; ///< this tick's heard-only entities, increasing
    std::uint64_t tick_ = 0;
};

} // namespace dsoc::inspect
