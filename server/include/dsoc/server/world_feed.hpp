#pragma once
// A gateway's side of a scaled-out world (ServerConfig::role "gateway";
// docs/scale-out.md): the world process's ticks as they arrive over NATS, the entity
// ids the world reserved for this gateway's new players, and what the gateway sends
// back (joins, its clients' inputs, leaves). Used on the server's I/O thread; the NATS
// client's threads only decode and hand over.
//
// A tick is taken newest first: when several arrived since the last one was taken (the
// gateway fell behind), only the newest is served and the others are counted as
// skipped, so clients get the present world late rather than a backlog of past ones.
//
// Faults it repairs (GatewayIds has the rules): a taken tick is checked against this
// gateway's players, and joins and leaves it shows lost are sent again. A tick of
// another world instance than the one followed is refused while that one is live (heard
// within kWorldSilence: a second world process on the same name does not take the
// gateway over, nor a stray message); once it is silent, the other instance is followed
// from its own tick 1 (the world process restarted): the ids of the old one are
// forgotten, the server is told to end every session that holds one (take_newest()),
// and fresh ids are reserved at once, as many as those sessions held (their clients
// come back together) and a block more. An id block is taken only of the instance
// followed: a gateway asks for ids once it follows one (its first tick), of that one
// alone.
//
// Tick numbers: the first tick taken of an instance must be plausible (kMaxFirstTick),
// and each later one newer than the last taken and no further ahead of it than the
// world can step in the time between them by its own clock (WorldTick::published_ns:
// kMaxTickRate a second, and a second more), so that no corrupt or hostile tick
// (numbered 2^64 - 1, say) makes the gateway refuse every tick after it or its own tick
// numbers wrap; refused ticks are counted as bad, with the reason, and the gateway
// carries on with the next good one. Should the instance's ticks all go back from the
// last one taken for kWorldSilence (that one was forged with a publish time to match),
// the gateway follows the instance anew from its present tick (world_resyncs).
// The gateway's own tick numbers (TakenTick::number) advance by the world's steps,
// keep increasing across restarts and resyncs, and stay below kMaxNumber.
//
// Whatever the gateway sends names a world instance: joins, inputs and leaves the one
// whose tick the server took last (so that none of a past world's sessions reaches the
// next), a reserve request the one followed.

#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_messages.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "dsoc/server/gateway_ids.hpp"
#include "dsoc/server/server_config.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::server {

struct WorldFeedStats {
    std::uint64_t ticks_received = 0; ///< decoded and for this world
    std::uint64_t ticks_skipped = 0;  ///< replaced by a newer one before they were served
    /// Ticks or id blocks that did not decode, were of another world, went back in time or
    /// jumped further ahead than the world's clock allows.
    std::uint64_t bad_messages = 0;
    std::uint64_t id_blocks = 0;     ///< blocks of entity ids the world reserved for us
    std::uint64_t ids_left = 0;      ///< of those, not given to a player yet
    std::uint64_t not_sent = 0;      ///< joins, inputs or leaves the NATS link refused
    std::uint64_t joins_resent = 0;  ///< players a tick lacked after their join was sent
    std::uint64_t leaves_resent = 0; ///< left players a tick still showed
    /// Players whose joins were given up (GatewayIds::kJoinResends): the world did not
    /// hold their ids for this gateway any more; their sessions ended with try_again.
    std::uint64_t joins_abandoned = 0;
    /// Ids not given out yet dropped as void with an abandoned join's block. [Units: ids]
    std::uint64_t ids_voided = 0;
    std::uint64_t world_restarts = 0; ///< new world instances followed after a first one
    /// The instance followed taken up anew at its present tick: every tick of it had gone
    /// back from the last one taken for kWorldSilence (that one was forged).
    std::uint64_t world_resyncs = 0;
    /// Ticks of another world instance, refused while the one followed was live (a
    /// restarted world's first ones; steadily: a second world on this name), and id
    /// blocks of an instance not followed (an answer that came after a switch).
    std::uint64_t other_instance = 0;
    std::uint64_t nats_disconnects = 0;
    std::uint64_t nats_reconnects = 0;
    std::string last_error; ///< why the last bad message was refused
};

/// The world process restarted: the instance that replaced the one the gateway followed.
struct WorldRestart {
    std::uint64_t old_instance = 0;
    std::uint64_t new_instance = 0;
};

/// A world tick as the server takes it.
struct TakenTick {
    scaleout::WorldTick tick;
    /// The gateway's own tick number: greater than every one taken before (across world
    /// restarts too), ahead of the last by as many steps as the world made (by a guess
    /// from above after a resync), below WorldFeed::kMaxNumber. [Units: ticks]
    std::uint64_t number = 0;
    /// Set on the first tick taken after the world process restarted: every entity id the
    /// gateway gave out before is void (the new world hands the same numbers to others),
    /// so every session holding one must end.
    std::optional<WorldRestart> restart;
    /// Entity ids whose joins were given up at this tick (GatewayIds::check): the world
    /// does not hold them for this gateway (it forgot the gateway), so the sessions
    /// holding them must end; their leaves are sent already.
    std::vector<std::uint32_t> abandoned;
};

class WorldFeed {
public:
    /// `on_tick` runs on `io`'s thread after each tick arrives; `wake` (optional, any
    /// thread) is called right after it is posted, for a loop that gathers events
    /// (io_loop.hpp) to take it up at once. Connects to config.nats_url (throws
    /// scaleout::NatsError when no server answers) and subscribes; the first block of ids
    /// is asked for at the first tick, of the world instance it names.
    WorldFeed(boost::asio::io_context& io, const ServerConfig& config, std::uint64_t world_key,
              std::function<void()> on_tick, std::function<void()> wake = {});
    ~WorldFeed();
    WorldFeed(const WorldFeed&) = delete;
    WorldFeed& operator=(const WorldFeed&) = delete;

    /// The newest tick not served yet (nothing when none arrived since the last call),
    /// after sending again the joins and leaves it shows lost (GatewayIds::check), and
    /// the leaves of the joins it gives up (TakenTick::abandoned).
    [[nodiscard]] std::optional<TakenTick> take_newest();
    /// Whether a tick waits to be taken.
    [[nodiscard]] bool tick_waiting() const;
    /// An entity id for a new player, or 0 when there is none yet: no world tick heard
    /// yet, the world has not reserved enough for us (unreachable, or not answered yet:
    /// the demand grows, so the next request asks for more) or a restart of the world has
    /// not been taken yet; `why_not`, when given, then says which. Asks for more before
    /// they run out.
    [[nodiscard]] std::uint32_t take_entity_id(std::string* why_not = nullptr);

    /// Sends the joins (leaves) of those of `entity_ids` that take_entity_id() gave out
    /// since the world instance followed now was first heard of (any other is void:
    /// nothing is sent for it).
    void send_joins(std::span<const std::uint32_t> entity_ids);
    void send_inputs(std::span<const scaleout::PlayerInput> inputs);
    void send_leaves(std::span<const std::uint32_t> entity_ids);

    [[nodiscard]] WorldFeedStats stats() const;

    /// How long the world instance followed must have been silent before another one is
    /// followed: far longer than a live world's period, short beside a restart. [Units: ms]
    static constexpr std::chrono::milliseconds kWorldSilence{1000};
    /// The first tick taken of a world instance is at most this: a world process steps
    /// at most 240 times a second (ServerConfig::tick_rate), so 2^40 is 145 years of
    /// its life; a larger one is refused (counted as bad) and does not take the gateway
    /// over. Beyond it, the gateway's tick numbers (the world's plus those served under
    /// earlier instances) could wrap. [Units: ticks]
    static constexpr std::uint64_t kMaxFirstTick = std::uint64_t{1} << 40;
    /// The gateway's own tick numbers stay below this: a tick that would take them past
    /// it is refused (counted as bad), so that nothing adding a duration to one wraps.
    /// Out of reach of a world's steps, however long the gateway runs. [Units: ticks]
    static constexpr std::uint64_t kMaxNumber = std::uint64_t{1} << 62;

private:
    void on_tick_message(const scaleout::NatsMessage& message);
    void on_block_message(const scaleout::NatsMessage& message);
    /// Whether a tick of world `instance` is to be taken (under mutex_): one of the
    /// instance followed, or of another once that one is silent (followed from now on; a
    /// restart when one was followed before: its ids are forgotten).
    bool follow(std::uint64_t instance);
    /// Counts a refused message as bad and why (under mutex_); logs a warning now and
    /// then.
    void refuse(std::string why);
    /// Whether `tick` may be taken as the first of its instance (under mutex_): not beyond
    /// kMaxFirstTick. Refuses it when not.
    bool plausible_start(const scaleout::WorldTick& tick, const std::string& subject);
    /// The gateway's number for `tick`, of the instance followed, arrived at `now` (under
    /// mutex_): nothing, after refusing it, when it is not newer than the last taken (but
    /// for a resync), jumps further than the world's clock allows, or its number would
    /// pass kMaxNumber.
    std::optional<std::uint64_t> number_of(const scaleout::WorldTick& tick,
                                           const std::string& subject,
                                           std::chrono::steady_clock::time_point now);
    /// Asks the instance followed (none before one is) for a block when
    /// GatewayIds::to_reserve() wants one and none was asked for within the last second
    /// (or the one asked for was of a past instance).
    void maybe_reserve();
    /// Who sends, for a batch: this gateway and the instance served (0: none yet).
    [[nodiscard]] scaleout::BatchFrom batch_from() const;
    void send(const std::string& what, const std::vector<std::byte>& bytes);
    /// A join (leave) batch of `entity_ids`, when there are any.
    void send_batch(scaleout::IdBatchKind kind, std::span<const std::uint32_t> entity_ids);
    /// Records `entity_ids` as joined (left) in ids_ and sends those given out.
    void send_ids(scaleout::IdBatchKind kind, std::span<const std::uint32_t> entity_ids);

    boost::asio::io_context& io_;
    std::string world_name_;
    std::uint64_t world_key_;
    std::uint64_t gateway_id_; ///< this gateway's id in its messages to the world
    std::function<void()> on_tick_;
    std::function<void()> wake_;
    std::unique_ptr<scaleout::NatsLink> link_;
    std::string inbox_;
    std::vector<std::byte> bytes_;

    mutable std::mutex mutex_; ///< the NATS threads' hand-over
    std::optional<scaleout::WorldTick> newest_;
    std::uint64_t instance_ = 0; ///< the world instance followed (0: none heard of yet)
    std::chrono::steady_clock::time_point heard_{}; ///< its last tick or block
    std::uint64_t last_tick_ = 0; ///< the newest tick of it accepted; older ones are refused
    /// That tick's WorldTick::published_ns, when it arrived, and its TakenTick::number
    /// (the last number of any instance); newest_'s number.
    std::uint64_t last_published_ = 0;
    std::chrono::steady_clock::time_point accepted_at_{};
    std::uint64_t last_number_ = 0;
    std::uint64_t newest_number_ = 0;
    /// When refused messages were last logged, and how many since.
    std::chrono::steady_clock::time_point refusal_logged_{};
    std::uint64_t refused_unlogged_ = 0;
    /// The instance of the last tick taken (0: none yet): named in joins, inputs, leaves.
    std::uint64_t served_ = 0;
    std::optional<WorldRestart> restart_; ///< not taken by the server yet
    GatewayIds ids_;                      ///< of the instance followed
    WorldFeedStats stats_;
    std::chrono::steady_clock::time_point last_reserve_{};
    bool reserve_pending_ = false; ///< asked, and no block of the instance followed since

    std::unique_ptr<scaleout::NatsSubscription> tick_sub_;
    std::unique_ptr<scaleout::NatsSubscription> block_sub_;
};

} // namespace dsoc::server
