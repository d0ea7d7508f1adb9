#pragma once
// InterestManager's private state (internal header): the per-entity slot, the
// per-client slot with its (client, entity) pairs, TBV groups and entity clusters,
// and the constants the manager's rules share. Every interest_manager_*.cpp file
// includes it; nothing outside visibility/src does.
//
// Files, by job:
//   interest_manager.cpp             construction, the registry of entities and
//                                    clients, queries
//   interest_manager_tick.cpp        the tick: begin_update() and update_client(),
//                                    each step a named function; eye regions
//   interest_manager_tbvs.cpp        making a TBV for a hidden entity (durations,
//                                    boxes, merging with this tick's groups)
//   interest_manager_tbv_groups.cpp  the TBV group pool of each client
//   interest_manager_clusters.cpp    entity clusters: grouping, testing, hiding
//   interest_manager_decisions.cpp   the replication set, its level of detail and
//                                    the enter/leave lists
//   interest_manager_validate.cpp    the invariant checker (ValidateDSOCState)

#include "dsoc/visibility/interest_manager.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <queue>
#include <vector>

namespace dsoc::visibility {

namespace detail {

inline constexpr std::uint32_t kNoGroup = 0xffffffffu;
/// Slack for float noise when checking a move against the motion limits. [Units: world units]
inline constexpr float kTeleportTolerance = 0.05f;
/// Groups created this tick that a new TBV may join (bounds the merge scan).
inline constexpr std::size_t kMergeCandidates = 8;
/// A TBV may join a group that expires up to this many ticks before it does (and is
/// then cut short to the group's expiry). [Units: ticks]
inline constexpr std::uint64_t kMergeExpirySlack = 4;
/// Candidate TBV durations tried per hide (each half the previous).
inline constexpr int kMaxTbvAttempts = 3;
/// After every candidate TBV was visible, the entity is only box-tested for this many
/// ticks before TBVs are tried again (entities at the edge of visibility would
/// otherwise pay for failed TBV tests every tick). [Units: ticks]
inline constexpr std::uint64_t kTbvRetryTicks = 8;
/// No entity cluster. Clusters of fewer members are not worth a test of their own.
inline constexpr std::uint32_t kNoCluster = 0xffffffffu;
inline constexpr std::size_t kMinClusterMembers = 3;

/// A box the manager accepts: finite and not empty.
inline bool valid_box(const Aabb& b) {
    return std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) &&
           std::isfinite(b.max.x) && std::isfinite(b.max.y) && std::isfinite(b.max.z) &&
           !b.is_empty();
}

} // namespace detail

struct InterestManager::EntitySlot {
    // `prepared` is what a client's test reads of the slot for every entity (the rest
    // of that pass reads EntityView): it sits in the slot's first cache lines.
    EntityId id = 0;
    bool alive = false;
    Aabb box;
    PreparedBox prepared; ///< `box` prepared for the culler, once per tick for all clients
    EntityDesc desc;
    Aabb box_at_last_update;
    bool seen_by_update = false;
    std::uint64_t teleported_at = 0; ///< tick of the last detected jump (0: never)
    float speed_per_tick = 0.0f;     ///< horizontal, from the last two updates
    float down_velocity = -1.0f;     ///< current downward speed, < 0 when unknown
    MovementHistory history;
    /// With a prepared stage: candidate TBVs made at tick `candidates_tick` (durations
    /// d, d/2, d/4; 0 ends the list), prepared once and shared by every client that hides
    /// the entity before they expire. A TBV depends on the entity alone; only whether it
    /// is hidden depends on the client.
    std::array<PreparedBox, detail::kMaxTbvAttempts> tbv_candidates;
    std::array<int, detail::kMaxTbvAttempts> tbv_durations{};
    std::uint64_t candidates_tick = 0;
    bool has_candidates = false;
    /// TBVs the entity held across all clients when this tick began: the per-object
    /// cap reads this, not the live counter, so decisions do not depend on the order
    /// in which parallel update_client() calls run.
    std::int32_t tbvs_at_tick_start = 0;

    /// `prepared` (and the entity's cluster box) is current: the box was not set after
    /// begin_update().
    [[nodiscard]] bool prepared_is_current() const {
        return prepared.box.min == box.min && prepared.box.max == box.max;
    }
};

/// The fields of an entity slot that every client's steps read for every entity each
/// tick (test_entities(), decide()), packed two to a cache line: the slots themselves
/// are hundreds of bytes apart, and 500 clients walking them paid a cache miss per
/// entity. Kept equal to the slot's fields by the registry and begin_update() (the
/// invariant checker compares them). Whether the slot is alive, its team and whether
/// its preparation is current are columns of their own beside it (view_alive_,
/// view_team_, view_fresh_): decide() reads the first two sixteen slots at a time, and
/// the pass over a hidden cluster's members the third alone.
struct InterestManager::EntityView {
    Aabb box;        ///< EntitySlot::box
    EntityId id = 0; ///< EntitySlot::id
};

struct InterestManager::TbvGroup {
    Aabb box;
    /// With a prepared stage: the union of the members' TBV keys. The group is hidden
    /// while the cheap stage proves every member TBV hidden (see hide()).
    PreparedBox prepared;
    std::uint64_t expiry = 0; ///< last tick the group is valid
    std::uint32_t generation = 0;
    bool alive = false;
    std::vector<std::uint32_t> members; ///< entity slots
};

/// Entities whose box centres share a cell of DSOCConfig::entity_cluster_size.
struct InterestManager::EntityCluster {
    PreparedBox prepared;               ///< union of the members' boxes at begin_update()
    std::vector<std::uint32_t> members; ///< entity slots, increasing
};

struct InterestManager::ClientSlot {
    /// A pair's TBV bookkeeping; its state is in `states` and its hint in `hints`
    /// (scanned every tick, so apart from these, which only TBVs use).
    struct Pair {
        std::uint32_t group = detail::kNoGroup;
        /// No TBV is tried before this tick (back-off after a rejected TBV).
        std::uint64_t next_tbv_tick = 0;
    };
    struct Expiry {
        std::uint64_t tick;
        std::uint32_t group;
        std::uint32_t generation;
        bool operator>(const Expiry& o) const { return tick > o.tick; }
    };

    ClientSlot(ClientId client_id, const ClientDesc& d, const LooseOctreeConfig& tree_config,
               std::unique_ptr<RegionVisibility> v)
        : id(client_id), desc(d), visibility(std::move(v)), tree(tree_config) {}

    ClientId id;
    ClientDesc desc;
    glm::vec3 eye{0.0f}; ///< at the last update
    glm::vec3 spectator_eye{0.0f};
    bool has_spectator_eye = false;
    std::unique_ptr<RegionVisibility> visibility; ///< built for buffer_region (TBVs)
    /// Built every tick for `region` alone, for the current boxes (exact_region_tests);
    /// made on first use.
    std::unique_ptr<RegionVisibility> exact;
    Aabb buffer_region;
    Aabb region;
    std::vector<PairState> states; // by entity slot
    std::vector<Pair> pairs;       // by entity slot
    /// By entity slot: the culler's hint for the pair's box (test_prepared_hinted), e.g.
    /// its last blocker; 0 for none.
    std::vector<std::uint32_t> hints;
    TeamId team = kNoTeam; // set_client_team()
    /// By entity slot: 0 for the team rule, else 1 + the pair's own Relevance.
    std::vector<std::uint8_t> rules;
    LooseOctree tree; // item id = group index
    std::vector<TbvGroup> groups;
    std::vector<std::uint32_t> free_groups;
    std::size_t live_groups = 0;
    std::priority_queue<Expiry, std::vector<Expiry>, std::greater<>> expiries;
    std::vector<std::uint32_t> new_groups;
    std::vector<std::uint32_t> scratch;
    PreparedBox candidate; // hide()'s TBV candidate, reused
    /// By cluster, this tick: 0 not proven hidden, 1 proven hidden, 2 members decided
    /// (hide_cluster(), with TBVs only).
    std::vector<std::uint8_t> cluster_hidden;
    /// By cluster proven hidden this tick: the hint that proved it, lent to each member
    /// as test_entities() passes it (DSOCConfig::blocker_hints).
    std::vector<std::uint32_t> cluster_hint;
    std::vector<std::uint32_t> cluster_members; // hide_cluster()'s scratch
    std::vector<std::uint8_t> bulk_hidden;      // by slot
    std::vector<EntityId> previous;             // replicated ids of the last update, increasing
                                                // (kept only with desc.enter_leave)
    std::vector<std::uint32_t> kept_slots;      // decide()'s scratch
    ClientDecisions decisions;
    ClientStats stats;
};

} // namespace dsoc::visibility
