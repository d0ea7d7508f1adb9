#pragma once
// DSOC interest management for a game server: for every client, every tick, its
// replication set (and, unless the client opts out, which entities entered and left
// it). An entity hidden from a client gets a Temporal Bounding Volume (where it can be
// until the TBV expires); nothing about it is tested or sent while the TBV stays hidden
// from the client's whole reachable eye region. See docs/dsoc.md.
//
// Guarantee (conservative): if an entity's box is visible from any point of a
// client's reachable eye region at tick t (eye +- the client's motion limits over
// its lookahead), the entity is in that client's replication set at t - provided
// every entity moved within its declared MotionLimits and the RegionVisibility is
// conservative. A jump beyond the limits is detected and voids that entity's TBVs.
//
// Ids are the caller's (plain numbers, no generation): an id removed and added again
// between two updates is the same entity to its clients (no leave/enter); give a new
// entity a new id if clients must see it replaced. A "bad box" is empty or not finite.
// Memory: per client, one pair state per entity plus up to max_tbvs_per_client TBV
// groups; per tick, O(clients x entities) cheap tests at worst.
//
// Threading: add/remove/set_* and begin_update() must be serialized. After
// begin_update(tick), update_client(i) for distinct i may run in parallel (each
// touches only its own client's state and reads shared entity state); then read
// decisions(). update(tick) does all of it on the calling thread.

#include "dsoc/visibility/dsoc_config.hpp"
#include "dsoc/visibility/loose_octree.hpp"
#include "dsoc/visibility/region_visibility.hpp"
#include "dsoc/visibility/relevance.hpp"
#include "dsoc/visibility/tbv.hpp"

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <queue>
#include <unordered_map>
#include <vector>

namespace dsoc::visibility {

using EntityId = std::uint32_t;
using ClientId = std::uint32_t;
inline constexpr EntityId kNoEntity = 0xffffffffu;

/// Visibility state of one (client, entity) pair (guide: "Visibility States").
enum class PairState : std::uint8_t {
    unknown,         ///< not decided yet (new client or entity)
    visible,         ///< in the replication set; its box is tested every tick
    hidden_with_tbv, ///< hidden; its TBV is hidden from the client's region
    hidden_expired,  ///< hidden, no valid TBV: its box is tested every tick
};
[[nodiscard]] const char* to_string(PairState s) noexcept;

struct EntityDesc {
    /// Half extents of the entity's box. [Units: world units]
    glm::vec3 half_extents{15.0f, 15.0f, 28.0f};
    MotionLimits motion;
};

/// How a reachable eye region was made: the client's eye_motion over `seconds` from a
/// viewer falling at `down_velocity`. Default: unknown (`limits` null), e.g. for a
/// region grown for reuse, which is not the motion limits' box.
struct EyeReach {
    const MotionLimits* limits = nullptr;
    float seconds = 0.0f;        ///< [Units: s]
    float down_velocity = -1.0f; ///< [Units: world units/s] < 0 when unknown
};

/// Optional game knowledge that shrinks a client's reachable eye region: given the
/// eye, the region and how it was made, a box that still contains every eye the
/// client can reach (e.g. sim::ReachClipper: players do not walk through walls, and
/// fall no faster than gravity where no slope is in reach). Must be thread-safe;
/// called once or twice per client per tick.
using EyeRegionClipper =
    std::function<Aabb(glm::vec3 eye, const Aabb& region, const EyeReach& reach)>;

struct ClientDesc {
    /// The entity the client controls and views from; kNoEntity for a spectator
    /// (then set_client_eye() places the eye).
    EntityId viewer = kNoEntity;
    /// Eye position relative to the viewer entity's box centre. [Units: world units]
    glm::vec3 eye_offset{0.0f, 0.0f, 26.0f};
    /// How many ticks ahead the client's own movement must be covered: round trip +
    /// interpolation delay, in ticks. [Units: ticks] [Limit: >= 0]
    int lookahead_ticks = 5;
    /// How fast the eye can move (the viewer's limits). [Units: world units / s]
    MotionLimits eye_motion;
    /// Fill ClientDecisions::enter and leave at each update: a diff of the set against
    /// the last one, a pass over both. false leaves them empty, for a caller that keeps
    /// what it sent itself and reads only `replicated`.
    bool enter_leave = true;
};

/// One replicated entity with its network level-of-detail hint.
struct Replicated {
    EntityId id = 0;
    /// Send an update every this many ticks (1, 2 or 4). [Units: ticks]
    std::uint8_t update_interval = 1;
};

/// What changed for one client in the last update. Ids in increasing order. enter and
/// leave only with ClientDesc::enter_leave (else empty).
struct ClientDecisions {
    std::vector<EntityId> enter;        ///< newly replicated
    std::vector<Replicated> replicated; ///< the whole set after the update (enter included)
    std::vector<EntityId> leave;        ///< no longer replicated
};

/// How much of the culler one client's update may use.
enum class UpdateEffort : std::uint8_t {
    full, ///< every stage
    /// The culler's cheap prepared stage alone (a baked table, else the map's PVS) for
    /// every box, and no new TBVs or clusters: still conservative (a box is hidden only
    /// when that stage proves it), looser, and cheap; for a tick over its CPU budget.
    /// Without a prepared stage it is `full` (nothing is cheaper than its shortcuts).
    cheapest,
};

/// Counters since the client joined.
struct ClientStats {
    std::uint64_t buffer_builds = 0;
    std::uint64_t box_tests = 0; ///< current-box tests
    std::uint64_t tbv_tests = 0; ///< TBV and octree-node tests
    std::uint64_t tbvs_created = 0;
    std::uint64_t tbvs_merged = 0;   ///< TBVs that joined an existing group
    std::uint64_t tbvs_rejected = 0; ///< would have been visible at creation: none made
    std::uint64_t tbv_hits = 0;      ///< groups found visible after a rebuild
    std::uint64_t tbvs_expired = 0;
    std::uint64_t evictions = 0;
    std::uint64_t teleports = 0; ///< TBVs voided by a jump beyond the limits
    /// Fuzzy TBVs (TbvStrategy::fuzzy, predicted, not bounded) the entity was found
    /// outside of: voided and the entity's box tested that tick.
    std::uint64_t fuzzy_escapes = 0;
    std::uint64_t cluster_tests = 0; ///< entity clusters tested (DSOCConfig::entity_cluster_size)
    std::uint64_t cluster_hits = 0;  ///< clusters proven hidden: their entities need no own test
    std::uint64_t cheapest_updates = 0; ///< updates asked for UpdateEffort::cheapest
};

class InterestManager {
public:
    /// `world_bounds`: where entities live (sizes the TBV octrees). `make_visibility`
    /// makes each client's culler (called in add_client(), and once here for a culler
    /// that prepares boxes for all clients). Throws std::invalid_argument naming the
    /// first problem when `config` does not pass validate().
    InterestManager(const DSOCConfig& config, const Aabb& world_bounds,
                    RegionVisibilityFactory make_visibility, EyeRegionClipper clipper = {});
    ~InterestManager();
    InterestManager(const InterestManager&) = delete;
    InterestManager& operator=(const InterestManager&) = delete;

    // Entities. Ids are the caller's; false on a duplicate/unknown id, kNoEntity or a
    // bad box. A removed entity is in the `leave` list of every client that had it, at
    // the next update.
    bool add_entity(EntityId id, const EntityDesc& desc, const Aabb& box);
    bool remove_entity(EntityId id);
    /// The entity's box after this tick's movement, and its velocity when known
    /// (units/s; a non-finite value means unknown: then falls are bounded by
    /// down_speed alone). A move beyond its motion limits since the last update is a
    /// teleport: its TBVs are voided. The box must stay inside the world bounds
    /// given to the constructor (TBVs and eye regions are clipped to them).
    bool set_entity_box(EntityId id, const Aabb& box,
                        glm::vec3 velocity = glm::vec3(std::numeric_limits<float>::quiet_NaN()));

    // Clients. A client's first update decides every entity at once (batch TBV
    // creation); its viewer entity is always in its own set. A ClientDesc cannot be
    // changed: remove the client and add it again.
    bool add_client(ClientId id, const ClientDesc& desc);
    bool remove_client(ClientId id);
    /// Spectators only (no viewer entity): where the eye is this tick.
    bool set_client_eye(ClientId id, glm::vec3 eye);

    // Interest beyond sight (relevance.hpp). Take effect at the next update; false on
    // an unknown id. The client's own viewer entity is always in its set: no pair rule
    // may be set on it.
    /// The entity's team (kNoTeam: none, the default).
    bool set_entity_team(EntityId id, TeamId team);
    /// The client's team (kNoTeam: none, the default): entities of its team are
    /// `always` replicated unless a pair rule says otherwise.
    bool set_client_team(ClientId id, TeamId team);
    /// The pair's own rule, over the team rule; nothing: back to the team rule. Forgotten
    /// when either is removed.
    bool set_relevance(ClientId client, EntityId entity, std::optional<Relevance> rule);
    /// The rule the pair is under now (its own, else the team rule); sight for unknown ids.
    [[nodiscard]] Relevance relevance(ClientId client, EntityId entity) const;

    /// Everything for one tick: begin_update, then every client in turn. Ticks should
    /// increase; the time since the last update is the tick difference (1 if not).
    void update(std::uint64_t tick);
    /// Serial part of a tick: teleport detection, speeds, and the per-entity work shared
    /// by all clients (each box prepared for the culler; the entity's candidate TBVs).
    void begin_update(std::uint64_t tick);
    /// Per-client part; distinct indexes may run concurrently. index < client_count().
    void update_client(std::size_t index, UpdateEffort effort = UpdateEffort::full);

    [[nodiscard]] std::size_t client_count() const { return clients_.size(); }
    [[nodiscard]] ClientId client_at(std::size_t index) const;
    /// Decisions of the last update; nullptr for an unknown client. The pointer (like
    /// stats()) stays valid until that client is removed; its contents change at each
    /// update.
    [[nodiscard]] const ClientDecisions* decisions(ClientId id) const;
    [[nodiscard]] const ClientStats* stats(ClientId id) const;
    [[nodiscard]] PairState state(ClientId client, EntityId entity) const;
    /// The client's reachable eye region at the last update (empty before it).
    [[nodiscard]] Aabb eye_region(ClientId id) const;
    /// The rule behind it: every eye a client described by `desc` can reach from `eye`
    /// over its lookahead, falling at `down_velocity` (< 0: unknown), within the world
    /// bounds and clipped by the EyeRegionClipper.
    [[nodiscard]] Aabb reachable_eye_region(const ClientDesc& desc, glm::vec3 eye,
                                            float down_velocity) const;
    /// The TBV box holding `entity` for `client`, or an empty box.
    [[nodiscard]] Aabb tbv_of(ClientId client, EntityId entity) const;
    /// Live TBV groups of a client.
    [[nodiscard]] std::size_t tbv_count(ClientId id) const;
    [[nodiscard]] const DSOCConfig& config() const { return config_; }

    /// ValidateDSOCState: every invariant of the manager, in words; empty when all
    /// hold. No visible pair has a TBV; every hidden_with_tbv pair's group is alive,
    /// unexpired, in the client's octree with its box, and contains the entity's
    /// current box; group member lists match pair states.
    [[nodiscard]] std::vector<std::string> validate_state() const;
    /// validate_state(); throws std::logic_error naming the first broken invariant (and
    /// how many more) and `when` (e.g. "at tick 12") if any. update() calls it when
    /// DSOCConfig::validate_state is on; callers that run begin_update() and
    /// update_client() themselves call it once every client is updated.
    void require_valid_state(const std::string& when) const;

private:
    // Defined in the library's private interest_manager_state.hpp, with the map of
    // which source file does which job.
    struct EntitySlot;
    struct EntityView;
    struct ClientSlot;
    struct TbvGroup;
    struct EntityCluster;

    // begin_update(), per entity, in this order.
    /// A move beyond the entity's motion limits over `seconds` is a jump (teleported_at,
    /// history cleared); its horizontal speed per tick over `elapsed` ticks.
    void note_movement(EntitySlot& e, std::uint64_t elapsed, float seconds);
    /// The entity's box prepared once for every client's culler.
    void prepare_box(EntitySlot& e);
    /// With a prepared stage: the entity's shared candidate TBVs, made again when half
    /// the longest has run out or the entity jumped.
    void refresh_tbv_candidates(EntitySlot& e);
    /// Groups this tick's entities by cell of entity_cluster_size (begin_update()).
    void build_clusters();

    // update_client()'s steps, in this order.
    /// Without an eye: no pair stays visible (nothing may be known).
    void forget_visible(ClientSlot& c);
    /// Step 1: rebuilds the client's culler unless it may be reused for this tick's
    /// region; true when it was rebuilt.
    bool refresh_culler(ClientSlot& c);
    /// Step 1: the culler this tick's current boxes are tested against (built for this
    /// tick's region alone under exact_region_tests).
    const RegionVisibility& current_box_culler(ClientSlot& c, bool cheapest);
    /// Step 2: expired TBV groups free their entities (hidden_expired).
    void expire_tbvs(ClientSlot& c);
    /// Step 3: TBVs of entities that jumped, and fuzzy TBVs the entity has left, are void.
    void void_broken_tbvs(ClientSlot& c);
    /// Step 4, after a rebuild: every TBV group proves itself hidden again or is freed.
    void reprove_tbvs(ClientSlot& c);
    /// Step 5a: clusters whose box is hidden from `now` (ClientSlot::cluster_hidden).
    void test_clusters(ClientSlot& c, const RegionVisibility& now, std::uint32_t viewer,
                       bool cheapest);
    /// Step 5b: every entity without a hidden TBV, visible or hidden (hide()).
    /// test_entities() without TBVs and clusters behind a culler whose prepared tests
    /// are all its coarse one (RegionVisibility::prepared_tests_are_coarse()): the same
    /// answers, the prepared boxes answered in one pass.
    void test_entities_in_bulk(ClientSlot& c, const RegionVisibility& now, std::uint32_t viewer,
                               bool cheapest);
    void test_entities(ClientSlot& c, const RegionVisibility& now, std::uint32_t viewer,
                       bool cheapest);
    /// test_entities() without TBVs, with clusters: cluster by cluster, so that the
    /// members of a hidden cluster take its answer in a pass of their own and the slot
    /// pass visits only the others. The same answers: a pair's does not depend on the
    /// order the pairs are tested in.
    void test_entities_by_cluster(ClientSlot& c, const RegionVisibility& now, std::uint32_t viewer,
                                  bool cheapest);
    /// test_entities()'s own test of one alive entity that is not the viewer, holds no
    /// hidden TBV and is not hidden with its cluster: its current box, quick or full.
    void test_entity(ClientSlot& c, const RegionVisibility& now, std::uint32_t slot, bool cheapest);
    /// Step 6: the replication set, its level of detail, enter and leave.
    void decide(ClientSlot& c);
    /// decide()'s kept slots (keeps()) from `slot` on, sixteen at a time while sixteen
    /// are left (SSE2; none without it): writes them to `kept`, returns how many, and
    /// leaves `slot` at the first slot not looked at. With validate_state, decide()
    /// checks it against keeps() slot by slot.
    std::size_t kept_by_sixteen(const ClientSlot& c, std::uint32_t* kept,
                                std::uint32_t& slot) const;
    /// The rule of the pair (client, entity slot): its own, else the team rule.
    [[nodiscard]] Relevance rule_of(const ClientSlot& c, std::uint32_t slot) const;
    /// Whether decide() keeps the slot: alive, and replicated under rule_of() given
    /// whether the culler found it visible (the rule kept_by_sixteen() restates).
    [[nodiscard]] bool keeps(const ClientSlot& c, std::uint32_t slot) const;
    /// The entity slot of the client's viewer; 0xffffffff for none (a spectator, or a
    /// viewer entity not added).
    [[nodiscard]] std::uint32_t viewer_slot_of(const ClientSlot& c) const;
    /// The entity was visible last tick and is not due its staggered full test.
    [[nodiscard]] bool takes_quick_test(const ClientSlot& c, std::uint32_t slot) const;
    /// (tick + slot) mod full_test_interval: the pair's full test is due at 0.
    [[nodiscard]] std::uint32_t full_test_phase(std::uint32_t slot) const;
    /// full_test_phase(slot) == 0, from the column begin_update() filled.
    [[nodiscard]] bool full_test_due(std::uint32_t slot) const;

    // TBVs.
    [[nodiscard]] int tbv_duration(const EntitySlot& e) const;
    [[nodiscard]] Aabb tbv_box(const EntitySlot& e, int duration) const;
    /// Hides `slot` from `c`: with a TBV when one is allowed and proven, else expired.
    void hide(ClientSlot& c, std::uint32_t slot);
    /// With TBVs: hides every member of a cluster proven hidden that still needs a
    /// decision this tick: one TBV group for all of them when the union of their TBVs is
    /// hidden, else each on its own (hide()).
    void hide_cluster(ClientSlot& c, std::uint32_t cluster, std::uint32_t viewer_slot);

    // The TBV group pool.
    /// A new TBV group holding `prepared` until `expiry`, in the octree and the heap.
    std::uint32_t new_group(ClientSlot& c, const PreparedBox& prepared, std::uint64_t expiry);
    /// Makes `slot` a member of `group` (state hidden_with_tbv).
    void join_group(ClientSlot& c, std::uint32_t group, std::uint32_t slot);
    void release_group_member(ClientSlot& c, std::uint32_t slot);
    void free_group(ClientSlot& c, std::uint32_t group);
    std::uint32_t allocate_group(ClientSlot& c);
    /// Pops the heap's earliest entry; a live group's entities become hidden_expired
    /// and the group is freed. Returns how many entities it held (0: stale entry).
    std::size_t expire_earliest_group(ClientSlot& c);

    // Eye regions.
    /// The reachable eye region of `c` now; `eye` receives the present eye.
    [[nodiscard]] Aabb eye_region_for(const ClientSlot& c, glm::vec3& eye) const;
    /// `box` intersected with the world bounds (entities never leave them).
    [[nodiscard]] Aabb clip(const Aabb& box) const;

    DSOCConfig config_;
    Aabb world_bounds_;
    RegionVisibilityFactory make_visibility_;
    EyeRegionClipper clipper_;
    /// Prepares every entity's box once per tick for all clients (begin_update()).
    std::unique_ptr<RegionVisibility> preparer_;
    /// The culler has a cheap prepared stage (RegionVisibility::has_prepared_stage()):
    /// TBVs are proven and re-proven by it alone, and a box test reads the entity's
    /// preparation. Without one a preparation is the box alone, and an entity's own
    /// test takes its box (test_entities()).
    bool prepared_stage_ = false;
    /// TBVs and entity clusters are used: the config asks for them and the culler's
    /// tests are dear enough for them to pay (RegionVisibility::pair_shortcuts_pay()).
    bool tbvs_enabled_ = true;
    bool clusters_enabled_ = true;
    float tick_seconds_;
    std::uint64_t tick_ = 0;
    std::vector<EntitySlot> entities_;
    /// By slot, beside entities_: what every client's steps read of each entity,
    /// packed (see EntityView).
    std::vector<EntityView> views_;
    /// By slot, beside views_: 1 when the slot holds an entity (EntitySlot::alive), and
    /// the entity's team (set_entity_team()).
    std::vector<std::uint8_t> view_alive_;
    std::vector<TeamId> view_team_;
    /// By slot, beside views_: 1 when the slot holds an entity whose preparation (and its
    /// cluster's box) is current, EntitySlot::prepared_is_current(): its box was not set
    /// after begin_update(). 0 for a free slot.
    std::vector<std::uint8_t> view_fresh_;
    /// By slot, at begin_update(): 1 when the pair's staggered full test is due this tick
    /// (full_test_phase() is 0), for every client.
    std::vector<std::uint8_t> full_test_due_;
    /// By entity slot, at begin_update(): the boxes prepared that tick (null when not
    /// alive), for test_entities_in_bulk(); empty when TBVs or clusters are on.
    PackedPreparedBoxes packed_boxes_;
    std::vector<std::uint32_t> free_entity_slots_;
    std::unordered_map<EntityId, std::uint32_t> entity_slot_;
    std::vector<std::unique_ptr<ClientSlot>> clients_;
    std::unordered_map<ClientId, std::size_t> client_index_;
    /// TBVs each entity slot holds across all clients; updated by concurrent
    /// update_client() calls (deque: stable addresses for the atomics).
    std::deque<std::atomic<std::int32_t>> tbv_counts_;
    /// Entity clusters of this tick (begin_update(); read-only during update_client()):
    /// the first cluster_count_ entries are live, the rest keep their memory.
    std::vector<EntityCluster> clusters_;
    std::size_t cluster_count_ = 0;
    std::vector<std::uint32_t> cluster_of_; ///< by entity slot; kNoCluster when none
    /// The slots below cluster_of_.size() in no cluster's members: empty at begin_update()
    /// (an entity added there since is tested on its own).
    std::vector<std::uint32_t> unlisted_slots_;
    std::unordered_map<std::uint64_t, std::uint32_t> cluster_cells_;
};

} // namespace dsoc::visibility
