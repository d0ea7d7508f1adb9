#pragma once
// The authoritative world of a scaled-out game (docs/scale-out.md): it moves every
// entity, takes joins, inputs and leaves from the interest gateways over NATS and
// publishes each tick's state (world_tick.hpp) for them to mirror. It knows no client
// and no socket: gateways hold those.
//
// Subjects, under "dsoc.<world name>.":
//   tick    - published after every step: the world tick, stamped with this process's
//             instance (random at every start: gateways tell a restarted world by it);
//   reserve - request (a gateway and a count) -> IdBlock: entity ids reserved for that
//             gateway, which it gives its new players (so that a hello is answered at
//             once, without a round trip);
//   gateway - a gateway's joins (ids from its blocks, spawned at the next step), input
//             batches (applied at the next step, the newest per player; one each
//             tick, empty or not: its heartbeat) and leaves (removed at the next
//             step), on one subject so that they arrive in the order it sent them.
// Each joined player belongs to the gateway that joined it: only that gateway's inputs
// and leave touch it. When a gateway has not been heard for `gateway_timeout` (it was
// killed, or cut off) its players are removed at the next step and it is counted as
// lost; their ids stay reserved for it, so that a gateway that comes back re-joins them
// (its clients' sessions carry on), until room is needed for other gateways' ids.
// Joins and leaves may come more than once (a gateway re-sends what the ticks show
// lost: NATS delivers at most once): a join of a player its gateway has joined already
// and a leave of a player gone already change nothing.
// Every message from a gateway names the world instance it is for (the one whose ticks
// the gateway serves; a reserve request the one it follows): a message naming another
// instance is dropped, the gateway not taken as heard, so that
// a second world process on the same name (or one started while gateways still follow
// a dead one) reserves, spawns and steers nothing for gateways that follow another.
// Messages that do not decode, messages of another instance, and joins, inputs or
// leaves for ids that are neither the sender's players nor reserved for it, are dropped
// and counted by reason (stats()); the world carries on.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_messages.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace dsoc::scaleout {

/// "dsoc.<world>.<what>": the subjects a world and its gateways share.
[[nodiscard]] std::string world_subject(const std::string& world, const std::string& what);

struct WorldProcessStats {
    std::uint64_t ticks = 0;
    std::uint64_t ticks_not_published = 0; ///< the link refused the tick (no connection)
    std::uint64_t ids_reserved = 0;
    std::uint64_t joins = 0;
    std::uint64_t leaves = 0;
    std::uint64_t inputs = 0;       ///< applied
    std::uint64_t bad_messages = 0; ///< did not decode (logged by the caller)
    /// Joins of ids not reserved for the sender, inputs for entities that are not its
    /// players (bots, another gateway's, players who left), leaves of entities in the
    /// world that are not its players.
    std::uint64_t for_strangers = 0;
    /// Joins of players their gateway had joined already and leaves of players gone (or
    /// going at the next step) already: a gateway's re-sends; nothing changes.
    std::uint64_t repeated = 0;
    std::uint64_t gateways_lost = 0; ///< silent past the timeout: their players removed
    /// Lost gateways heard again: their re-joins bring their players back.
    std::uint64_t gateways_back = 0;
    /// Lost gateways whose ids were released to make room for other reservations: their
    /// re-joins, should they come back, are refused (as strangers').
    std::uint64_t gateways_forgotten = 0;
    /// Messages naming another world instance than this process's (a gateway that
    /// follows another world process on the same name): dropped unread.
    std::uint64_t other_instance = 0;
    /// Reserve requests refused because fewer ids than asked for are left below 2^32
    /// (interest::GameWorld::ids_left(): ids never wrap).
    std::uint64_t ids_exhausted = 0;
    std::string last_error; ///< why the last bad message was refused
};

class WorldProcess {
public:
    /// `link` must outlive this. Subscribes at once.
    WorldProcess(std::shared_ptr<const maps::Map> map, const interest::WorldSettings& settings,
                 int tick_rate, NatsLink& link, std::string world_name,
                 std::chrono::milliseconds gateway_timeout = kDefaultGatewayTimeout);
    /// How long a gateway may be silent before its players are removed: longer than a
    /// NATS restart, shorter than a client's patience for snapshots.
    static constexpr std::chrono::milliseconds kDefaultGatewayTimeout{3000};
    /// Ids reserved and not joined, over all gateways (lost ones' included), at most: a
    /// reserve request beyond it first forgets lost gateways, the longest lost first, and
    /// is refused (counted) if that is not enough, so no publisher can make the world
    /// hold ids without end.
    static constexpr std::size_t kMaxReserved = 65'536;
    ~WorldProcess();
    WorldProcess(const WorldProcess&) = delete;
    WorldProcess& operator=(const WorldProcess&) = delete;

    /// One world tick: the joins, leaves and newest inputs that arrived since the last,
    /// then a step of 1 / tick_rate s, then the tick published. Serial.
    void tick();

    [[nodiscard]] WorldProcessStats stats() const;
    [[nodiscard]] std::uint64_t world_key() const { return key_; }
    /// This process's instance: random, never 0, in every tick and id block.
    [[nodiscard]] std::uint64_t instance() const { return instance_; }
    /// Messages of any kind received so far (tests wait on it).
    [[nodiscard]] std::uint64_t messages_received() const { return received_.load(); }
    /// A copy of the world, taken under the lock: the NATS callbacks change it between
    /// ticks (a reserve request takes ids from it), so no reference is handed out.
    [[nodiscard]] interest::GameWorld world() const {
        const std::lock_guard lock(mutex_);
        return world_;
    }

private:
    void on_reserve(const NatsMessage& message);
    /// A message on the `gateway` subject, to the handler its magic names.
    void on_gateway(const NatsMessage& message);
    void on_join(const NatsMessage& message);
    void on_input(const NatsMessage& message);
    void on_leave(const NatsMessage& message);
    /// Counts a message that did not decode, and why (under mutex_, as what follows).
    void refuse(const std::string& why);
    /// Whether a message naming world `instance` is for this process; counts it when not.
    bool for_us(std::uint64_t instance);
    /// Reserves `count` ids for `gateway` (under mutex_); the block, or nothing when they
    /// do not fit under kMaxReserved or below 2^32 (refused and counted).
    std::optional<IdBlock> reserve_for(std::uint64_t gateway, std::uint32_t count,
                                       const std::string& subject);
    /// Whether `decoded` decoded; refuses it when not.
    template <typename T>
    bool accepted(const maps::Result<T>& decoded);

    /// A gateway as the world knows it.
    struct Gateway {
        std::chrono::steady_clock::time_point last_heard;
        std::set<std::uint32_t> players; ///< joined: spawned at the next step, or since
        /// Reserved for it and not joined: ids of its blocks, and its players removed
        /// while it was lost (a re-join brings them back).
        std::set<std::uint32_t> reserved;
        /// 0 while heard within the timeout; once lost, the order of its loss (the
        /// longest lost is forgotten first).
        std::uint64_t lost = 0;
    };
    /// The gateway `id`, now heard from: created when new, back when it was lost.
    Gateway& heard_from(std::uint64_t id);
    /// Whether `count` more ids fit under kMaxReserved, forgetting lost gateways (the
    /// longest lost first) as far as needed.
    bool make_room(std::size_t count);
    /// Removes the players of every gateway silent past the timeout at `now`, keeping
    /// their ids reserved for it.
    void lose_silent_gateways(std::chrono::steady_clock::time_point now);
    /// tick(): spawns the players joined since the last step and removes those leaving,
    /// each kind in one pass over the world (under mutex_).
    void spawn_and_remove();

    interest::GameWorld world_;
    float dt_;
    NatsLink& link_;
    std::string name_;
    std::uint64_t key_;
    std::uint64_t instance_;
    std::uint64_t tick_ = 0;
    std::vector<std::byte> bytes_;

    mutable std::mutex mutex_; ///< what the callbacks hand to tick(), and the stats
    /// Joined since the last step: (gateway, id).
    std::vector<std::pair<std::uint64_t, std::uint32_t>> joining_;
    std::vector<std::uint32_t> spawning_; ///< tick(): joining_'s ids still to spawn
    std::unordered_map<std::uint32_t, PlayerInput> inputs_; ///< newest per entity
    std::vector<std::uint32_t> leaving_;

    std::chrono::milliseconds gateway_timeout_;
    std::uint64_t seen_reconnects_ = 0; ///< the link's reconnections tick() has seen
    std::unordered_map<std::uint64_t, Gateway> gateways_;
    std::size_t reserved_ = 0; ///< ids in every gateway's `reserved`
    std::uint64_t losses_ = 0; ///< gateways lost so far: the next one's Gateway::lost
    WorldProcessStats stats_;
    std::atomic<std::uint64_t> received_{0};

    std::unique_ptr<NatsSubscription> reserve_sub_;
    std::unique_ptr<NatsSubscription> gateway_sub_;
};

} // namespace dsoc::scaleout
