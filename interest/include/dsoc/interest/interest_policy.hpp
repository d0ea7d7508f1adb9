#pragma once
// Interest policies decide, per tick and per client, which entities the client
// should know about. The server turns the answer into enter/update/leave messages;
// dsoc-inspect draws it; dsoc-eval runs the same policies over its recorded frames
// (a WorldView) and judges them.
//
// Threading: begin_tick(), add_viewer() and remove_viewer() are serialized (the
// server's tick thread). After begin_tick(), select() may run concurrently for
// distinct viewers (the server's worker pool); its answer for a viewer depends only
// on the world, the tick and that viewer, never on the order or the thread.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/policy_choices.hpp"
#include "dsoc/interest/world_view.hpp"
#include "dsoc/maps/pvs.hpp"
#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/dsoc_config.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::interest {

/// The tier of an entity a client is sent only because it hears it (hearing.hpp): a
/// coarse position, no view angles (protocol::kHeardTier).
inline constexpr std::uint8_t kHeardTier = 3;

/// One entity of a client's interest set, with its network level-of-detail tier.
struct Interest {
    std::uint32_t id = 0;
    /// 0 near: updated every tick at the finest quantum; 1 mid: every 2nd tick, coarser;
    /// 2 far: every 4th tick, coarsest (the server's position quanta). Policies
    /// without a distance hint answer 0. kHeardTier: heard, not seen (Hearing).
    std::uint8_t tier = 0;
    friend bool operator==(const Interest&, const Interest&) = default;
};

/// One client's point of view this tick.
struct Viewer {
    std::uint32_t client_id = 0;
    std::uint32_t entity_id = 0; ///< the entity the client controls
    glm::vec3 eye{0.0f};
    /// Where a respawn the world has decided will put the eye, within the client's
    /// latency allowance (EntityView::arrival_eye of its entity); nothing while it
    /// lives. Every policy answers for both eyes, so what the client sees on arrival
    /// is known before it gets there.
    std::optional<glm::vec3> arrival_eye;
    /// The team of its entity (visibility::kNoTeam: none). Every policy sends the
    /// entities of the viewer's team whatever it sees (visibility::team_relevance()).
    visibility::TeamId team = visibility::kNoTeam;
};

/// Client `client_id`'s point of view from its entity `self` of `world` this tick.
[[nodiscard]] inline Viewer viewer_of(const GameWorld& world, std::uint32_t client_id,
                                      const Entity& self) {
    return {client_id, self.id, world.eye_of(self), world.arrival_eye_of(self), self.team};
}

class InterestPolicy {
public:
    virtual ~InterestPolicy() = default;
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// Called once per tick after movement, before any select(). Serial.
    virtual void begin_tick(const WorldView& /*world*/, std::uint64_t /*tick*/) {}
    /// Fills `out` (cleared first) with the entities `viewer` should know, in
    /// increasing id order. The server adds the viewer's own entity itself. Call at most
    /// once per viewer per tick; concurrent calls for distinct viewers are safe.
    virtual void select(const WorldView& world, const Viewer& viewer,
                        std::vector<Interest>& out) = 0;
    /// select() at the least CPU the policy can answer with, still conservative for
    /// policies that are (a tick over its culling budget). The same call rules as
    /// select(), which it replaces for that viewer and tick. Default: select().
    virtual void select_cheapest(const WorldView& world, const Viewer& viewer,
                                 std::vector<Interest>& out) {
        select(world, viewer, out);
    }
    /// A client joined, viewing from `entity_id`; it gets its first snapshot after the
    /// next begin_tick().
    virtual void add_viewer(std::uint32_t /*client_id*/, std::uint32_t /*entity_id*/) {}
    /// A client left: forget any per-client state.
    virtual void remove_viewer(std::uint32_t /*client_id*/) {}
    /// Removes from `entity_ids` every entity a pair rule keeps from client `client_id`
    /// whatever it sees or hears (visibility::Relevance::never), keeping the order, for a
    /// policy with such rules (the built-in ones have only teams, which never deny:
    /// default, nothing). Called once per viewer and tick (Hearing::add_heard), for
    /// distinct viewers concurrently and beside select(): must be safe so.
    virtual void erase_denied(std::uint32_t /*client_id*/,
                              std::vector<std::uint32_t>& /*entity_ids*/) const {}
    /// Live TBV groups over all viewers (0 for policies without TBVs); for metrics.
    /// Serialized with begin_tick().
    [[nodiscard]] virtual std::size_t tbvs_alive() const { return 0; }
};

/// The distance policy's rule: `box` comes within `radius` of `eye` (its nearest point).
[[nodiscard]] inline bool within_radius(const visibility::Aabb& box, glm::vec3 eye, float radius) {
    return visibility::distance_squared(box, eye) <= radius * radius;
}
/// within_radius() of the viewer's eye or of its arrival eye.
[[nodiscard]] inline bool within_radius(const visibility::Aabb& box, const Viewer& viewer,
                                        float radius) {
    return within_radius(box, viewer.eye, radius) ||
           (viewer.arrival_eye && within_radius(box, *viewer.arrival_eye, radius));
}

/// The pvs policy's rule for the eye: `rows` becomes the union of the PVS rows of the
/// clusters `eye` is in (`clusters` is scratch), and an entity is sent when its box
/// touches one of them (maps::Pvs::may_see). False when that says nothing and
/// everything is sent: no PVS, a map without vis data, or an eye in solid.
[[nodiscard]] bool eye_pvs_rows(const maps::Pvs* pvs, glm::vec3 eye,
                                std::vector<std::int32_t>& clusters,
                                std::vector<std::uint8_t>& rows);
/// eye_pvs_rows() of the viewer's eye, ORed with those of its arrival eye when it has
/// one (`scratch` is scratch). False when either says nothing.
[[nodiscard]] bool viewer_pvs_rows(const maps::Pvs* pvs, const Viewer& viewer,
                                   std::vector<std::int32_t>& clusters,
                                   std::vector<std::uint8_t>& rows,
                                   std::vector<std::uint8_t>& scratch);

/// Every entity, always.
/// The entity ids are taken once per tick (begin_tick) for all clients.
class BroadcastPolicy final : public InterestPolicy {
public:
    [[nodiscard]] std::string_view name() const override { return "broadcast"; }
    void begin_tick(const WorldView& world, std::uint64_t tick) override;
    void select(const WorldView& world, const Viewer& viewer, std::vector<Interest>& out) override;

private:
    std::vector<std::uint32_t> ids_; // this tick's entities, increasing
};

/// Entities whose box comes within `radius` of the viewer's eye (ring culling, as in
/// Unreal's replication graph grid or Mirror's distance interest management). The
/// entities' ids and boxes are taken once per tick (begin_tick) for all clients.
class DistancePolicy final : public InterestPolicy {
public:
    explicit DistancePolicy(float radius) : radius_(radius) {}
    [[nodiscard]] std::string_view name() const override { return "distance"; }
    void begin_tick(const WorldView& world, std::uint64_t tick) override;
    void select(const WorldView& world, const Viewer& viewer, std::vector<Interest>& out) override;

private:
    float radius_;
    std::vector<std::uint32_t> ids_; // this tick's entities, increasing
    std::vector<visibility::Aabb> boxes_;
    std::vector<visibility::TeamId> teams_;
};

/// What the Quake 3 server does: an entity is sent when its box touches a leaf whose
/// cluster is in the map's PVS row of the viewer's eye cluster (areaportals left out).
/// Everything passes on maps without vis data and for eyes in solid.
/// Each entity's clusters are looked up once per tick (begin_tick) for all clients;
/// a client's select() then only tests bits of its eye cluster's row.
class PvsPolicy final : public InterestPolicy {
public:
    explicit PvsPolicy(std::shared_ptr<const maps::Pvs> pvs) : pvs_(std::move(pvs)) {}
    [[nodiscard]] std::string_view name() const override { return "pvs"; }
    void begin_tick(const WorldView& world, std::uint64_t tick) override;
    void select(const WorldView& world, const Viewer& viewer, std::vector<Interest>& out) override;

private:
    std::shared_ptr<const maps::Pvs> pvs_; ///< read-only after construction
    // This tick's entities (world order) and their clusters (Pvs::clusters_of), all in
    // one array, so that a viewer's pass reads them in order: entity i's at
    // [cluster_start_[i], cluster_start_[i + 1]). An entity in no clustered leaf, in a
    // cluster the PVS has no row for, or any without vis data, is always sent (has no
    // clusters here). Written by begin_tick(), read-only during select(); the vectors keep
    // their capacity.
    std::vector<std::uint32_t> ids_;
    std::vector<std::uint32_t> clusters_;
    std::vector<std::uint32_t> cluster_start_;
    std::vector<std::uint8_t> always_sent_;
    std::vector<visibility::TeamId> teams_;
    std::vector<std::int32_t> scratch_; ///< begin_tick()'s
};

/// What make_policy() reads: which policy, and the settings of the one it makes. The
/// defaults written here are the server's too (its ServerConfig takes them from here);
/// the server builds it from its own settings in one place
/// (dsoc::server::policy_settings()).
struct PolicySettings {
    /// Which policy (its names: kPolicyNames).
    PolicyKind policy = PolicyKind::dsoc;
    /// distance: the radius from the viewer's eye. [Units: world units] [Limit: > 0]
    float distance_radius = 1500.0f;
    /// dsoc and occlusion: the InterestManager's settings, the policy's presets
    /// included. Must pass visibility::validate().
    visibility::DSOCConfig dsoc;
    /// dsoc and occlusion: the exact occluder stages (their names: kCullerNames).
    CullerKind culler = CullerKind::shaft;
    /// Levels of portal tests in the shaft stage. [Limit: 0..4]
    int portal_depth = 0;
    /// The map's PVS over the reachable clusters before the exact stage.
    bool pvs_stage = true;
    /// The map's baked cell table before them (or alone): make_policy()'s `baked_table`.
    bool baked_stage = true;
    /// The cell edge the baked table was asked for. [Units: world units]
    float bake_cell_size = 32.0f;
    /// With baked_stage: whether the exact stages follow the table (use_exact_stages();
    /// the names "auto", "true", "false": kExactStagesNames).
    ExactStages exact_stages = ExactStages::when_coarse;
    /// The client latency allowance. [Units: ticks] [Limit: >= 0]
    int lookahead_ticks = 5;
};

/// PolicySettings::culler as the exact stages of `config`.
void set_culler_stages(CullerKind culler, visibility::RegionCullerConfig& config);

/// The occlusion policy's presets over `config` when `policy` is occlusion (every
/// entity's current box every tick: no TBVs, no culler reuse, no temporal coherence,
/// no blocker hints); other policies leave it as it is.
void apply_policy_presets(PolicyKind policy, visibility::DSOCConfig& config);

/// A latency allowance in whole ticks at `tick_rate`, rounded up: how far ahead a
/// client's own movement is covered (PolicySettings::lookahead_ticks).
[[nodiscard]] int lookahead_ticks(int latency_allowance_ms, int tick_rate);

/// The map's baked cell visibility table over the occluders of `scene`, for
/// PolicySettings::baked_stage. Throws when it cannot be had.
using BakedTableSource = std::function<std::shared_ptr<const visibility::CellVisibilityTable>(
    const visibility::OccluderScene& scene)>;

/// The policy named by settings.policy, for `world`; the settings must be usable
/// (dsoc::server::validate() checks the server's). `baked_table` is called once when a
/// culling policy (dsoc, occlusion) has baked_stage; std::invalid_argument when it is
/// needed and empty.
std::unique_ptr<InterestPolicy> make_policy(const PolicySettings& settings, const GameWorld& world,
                                            const BakedTableSource& baked_table = {});

/// Whether the exact stages follow `table` (PolicySettings::exact_stages; when_coarse:
/// when the bake had to make its cells coarser than settings.bake_cell_size).
[[nodiscard]] bool use_exact_stages(const PolicySettings& settings,
                                    const visibility::CellVisibilityTable& table);

} // namespace dsoc::interest
