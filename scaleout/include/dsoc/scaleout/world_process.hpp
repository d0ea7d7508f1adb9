#pragma once
// The authoritative world of a scaled-out game (docs/scale-out.md): it moves every
// entity, takes joins, inputs and leaves from the interest gateways over NATS and
// publishes each tick's state (world_tick.hpp) for them to mirror. It knows no client
// and no socket: gateways hold those.
//
// Subjects, under "dsoc.<world name>.":
//   tick    - published after every step: the world tick;
//   reserve - request (a count) -> IdBlock: entity ids the asking gateway gives its new
//             players (so that a hello is answered at once, without a round trip);
//   gateway - a gateway's joins (ids from its blocks, spawned at the next step), input
//             batches (applied at the next step, the newest per player; one each
//             tick, empty or not: its heartbeat) and leaves (removed at the next
//             step), on one subject so that they arrive in the order it sent them.
// Each joined player belongs to the gateway that joined it: only that gateway's inputs
// and leave touch it, and when a gateway has not been heard for `gateway_timeout` (it
// was killed, or cut off) its players are removed at the next step and it is counted
// as lost: its clients come back through another gateway as new players.
// Messages that do not decode, and joins, inputs or leaves for ids that are not
// reserved or joined players, are dropped and counted by reason (stats()); the world
// carries on.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_messages.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
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
    /// Joins of ids not reserved (or joined already), inputs and leaves for entities
    /// that are not joined players (bots, strangers, players who left).
    std::uint64_t for_strangers = 0;
    std::uint64_t gateways_lost = 0; ///< silent past the timeout: their players removed
    std::string last_error;          ///< why the last bad message was refused
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
    /// Ids reserved and not joined, over all gateways, at most: reserve requests beyond
    /// it are refused (counted), so no publisher can make the world hold ids without end.
    static constexpr std::size_t kMaxReserved = 65'536;
    ~WorldProcess();
    WorldProcess(const WorldProcess&) = delete;
    WorldProcess& operator=(const WorldProcess&) = delete;

    /// One world tick: the joins, leaves and newest inputs that arrived since the last,
    /// then a step of 1 / tick_rate s, then the tick published. Serial.
    void tick();

    [[nodiscard]] WorldProcessStats stats() const;
    [[nodiscard]] std::uint64_t world_key() const { return key_; }
    /// Messages of any kind received so far (tests wait on it).
    [[nodiscard]] std::uint64_t messages_received() const { return received_.load(); }
    [[nodiscard]] const interest::GameWorld& world() const { return world_; }

private:
    void on_reserve(const NatsMessage& message);
    /// A message on the `gateway` subject, to the handler its magic names.
    void on_gateway(const NatsMessage& message);
    void on_join(const NatsMessage& message);
    void on_input(const NatsMessage& message);
    void on_leave(const NatsMessage& message);
    /// Counts a message that did not decode, and why (under mutex_, as the next two).
    void refuse(const std::string& why);
    /// Whether `decoded` decoded; refuses it when not.
    template <typename T>
    bool accepted(const maps::Result<T>& decoded);
    /// Whether player `id` belongs to `gateway`; counted as a stranger's when not.
    bool owns(std::uint64_t gateway, std::uint32_t id);

    interest::GameWorld world_;
    float dt_;
    NatsLink& link_;
    std::string name_;
    std::uint64_t key_;
    std::uint64_t tick_ = 0;
    std::vector<std::byte> bytes_;

    mutable std::mutex mutex_; ///< what the callbacks hand to tick(), and the stats
    std::vector<std::uint32_t> joining_;
    std::unordered_map<std::uint32_t, PlayerInput> inputs_; ///< newest per entity
    std::vector<std::uint32_t> leaving_;
    /// A gateway as the world knows it: when it was last heard and its players.
    struct Gateway {
        std::chrono::steady_clock::time_point last_heard;
        std::set<std::uint32_t> players;
    };
    /// The gateway `id`, now heard from (created when new).
    Gateway& heard_from(std::uint64_t id);

    std::chrono::milliseconds gateway_timeout_;
    std::uint64_t seen_reconnects_ = 0; ///< the link's reconnections tick() has seen
    std::set<std::uint32_t> reserved_;  ///< handed out in blocks, not joined yet
    std::unordered_map<std::uint32_t, std::uint64_t> owner_; ///< joined player -> its gateway
    std::unordered_map<std::uint64_t, Gateway> gateways_;
    WorldProcessStats stats_;
    std::atomic<std::uint64_t> received_{0};

    std::unique_ptr<NatsSubscription> reserve_sub_;
    std::unique_ptr<NatsSubscription> gateway_sub_;
};

} // namespace dsoc::scaleout
