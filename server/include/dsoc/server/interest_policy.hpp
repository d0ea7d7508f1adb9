#pragma once
// Interest policies decide, per tick and per client, which entities the client
// should know about. The server turns the answer into enter/update/leave messages.
//
// Threading: begin_tick(), add_viewer() and remove_viewer() are serialized (the
// server's tick thread). After begin_tick(), select() may run concurrently for
// distinct viewers (the server's worker pool); its answer for a viewer depends only
// on the world, the tick and that viewer, never on the order or the thread.

#include "dsoc/server/game_world.hpp"
#include "dsoc/server/server_config.hpp"
#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

namespace dsoc::server {

/// One entity of a client's interest set, with its network level-of-detail tier.
struct Interest {
    std::uint32_t id = 0;
    /// 0 near: updated every tick at the finest quantum; 1 mid: every 2nd tick, coarser;
    /// 2 far: every 4th tick, coarsest (ServerConfig's position quanta). Policies
    /// without a distance hint answer 0.
    std::uint8_t tier = 0;
    friend bool operator==(const Interest&, const Interest&) = default;
};

/// One client's point of view this tick.
struct Viewer {
    std::uint32_t client_id = 0;
    std::uint32_t entity_id = 0; ///< the entity the client controls
    glm::vec3 eye{0.0f};
};

class InterestPolicy {
public:
    virtual ~InterestPolicy() = default;
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// Called once per tick after movement, before any select(). Serial.
    virtual void begin_tick(const GameWorld& /*world*/, std::uint64_t /*tick*/) {}
    /// Fills `out` (cleared first) with the entities `viewer` should know, in
    /// increasing id order. The server adds the viewer's own entity itself. Call at most
    /// once per viewer per tick; concurrent calls for distinct viewers are safe.
    virtual void select(const GameWorld& world, const Viewer& viewer,
                        std::vector<Interest>& out) = 0;
    /// select() at the least CPU the policy can answer with, still conservative for
    /// policies that are (a tick over its culling budget). The same call rules as
    /// select(), which it replaces for that viewer and tick. Default: select().
    virtual void select_cheapest(const GameWorld& world, const Viewer& viewer,
                                 std::vector<Interest>& out) {
        select(world, viewer, out);
    }
    /// A client joined, viewing from `entity_id`; it gets its first snapshot after the
    /// next begin_tick().
    virtual void add_viewer(std::uint32_t /*client_id*/, std::uint32_t /*entity_id*/) {}
    /// A client left: forget any per-client state.
    virtual void remove_viewer(std::uint32_t /*client_id*/) {}
    /// Live TBV groups over all viewers (0 for policies without TBVs); for metrics.
    /// Serialized with begin_tick().
    [[nodiscard]] virtual std::size_t tbvs_alive() const { return 0; }
};

/// Every entity, always.
class BroadcastPolicy final : public InterestPolicy {
public:
    [[nodiscard]] std::string_view name() const override { return "broadcast"; }
    void select(const GameWorld& world, const Viewer& viewer, std::vector<Interest>& out) override;
};

/// Entities whose box comes within `radius` of the viewer's eye (ring culling, as in
/// Unreal's replication graph grid or Mirror's distance interest management).
class DistancePolicy final : public InterestPolicy {
public:
    explicit DistancePolicy(float radius) : radius_(radius) {}
    [[nodiscard]] std::string_view name() const override { return "distance"; }
    void select(const GameWorld& world, const Viewer& viewer, std::vector<Interest>& out) override;

private:
    float radius_;
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
    void begin_tick(const GameWorld& world, std::uint64_t tick) override;
    void select(const GameWorld& world, const Viewer& viewer, std::vector<Interest>& out) override;

private:
    std::shared_ptr<const maps::Pvs> pvs_; ///< read-only after construction
    // This tick's entities (world order) and their clusters (Pvs::clusters_of); an
    // entity in no clustered leaf (or any, without vis data) is always sent. Written
    // by begin_tick(), read-only during select(); the vectors keep their capacity.
    std::vector<std::uint32_t> ids_;
    std::vector<std::vector<std::int32_t>> clusters_;
    std::vector<bool> always_sent_;
};

/// The policy named by config.policy, for `world`; config must have passed validate().
std::unique_ptr<InterestPolicy> make_policy(const ServerConfig& config, const GameWorld& world);

/// Whether the exact stages follow `table` (ServerConfig::exact_stages; "auto": when
/// the bake had to make its cells coarser than config.bake_cell_size).
[[nodiscard]] bool use_exact_stages(const ServerConfig& config,
                                    const visibility::CellVisibilityTable& table);

/// The map's baked cell visibility table for config.baked_stage: from the cache, or
/// baked (progress on stderr) and saved. Throws std::runtime_error when it cannot be had.
[[nodiscard]] std::shared_ptr<const visibility::CellVisibilityTable>
baked_table(const ServerConfig& config, const GameWorld& world,
            const visibility::OccluderScene& scene);

} // namespace dsoc::server
