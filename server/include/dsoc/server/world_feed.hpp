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

#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_messages.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "dsoc/server/server_config.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <cstdint>
#include <deque>
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
    std::uint64_t bad_messages = 0; ///< ticks or id blocks that did not decode, or of another world
    std::uint64_t id_blocks = 0;    ///< blocks of entity ids the world reserved for us
    std::uint64_t ids_left = 0;     ///< of those, not given to a player yet
    std::uint64_t not_sent = 0;     ///< joins, inputs or leaves the NATS link refused
    std::uint64_t nats_disconnects = 0;
    std::uint64_t nats_reconnects = 0;
    std::string last_error; ///< why the last bad message was refused
};

class WorldFeed {
public:
    /// `on_tick` runs on `io`'s thread after each tick arrives; `wake` (optional, any
    /// thread) is called right after it is posted, for a loop that gathers events
    /// (io_loop.hpp) to take it up at once. Connects to config.nats_url (throws
    /// scaleout::NatsError when no server answers), subscribes and asks the world for a
    /// first block of ids.
    WorldFeed(boost::asio::io_context& io, const ServerConfig& config, std::uint64_t world_key,
              std::function<void()> on_tick, std::function<void()> wake = {});
    ~WorldFeed();
    WorldFeed(const WorldFeed&) = delete;
    WorldFeed& operator=(const WorldFeed&) = delete;

    /// The newest tick not served yet (nothing when none arrived since the last call).
    [[nodiscard]] std::optional<scaleout::WorldTick> take_newest();
    /// Whether a tick waits to be taken.
    [[nodiscard]] bool tick_waiting() const;
    /// An entity id for a new player, or 0 when the world has not reserved any for us
    /// (unreachable, or not answered yet). Asks for more before they run out.
    [[nodiscard]] std::uint32_t take_entity_id();

    void send_joins(std::span<const std::uint32_t> entity_ids);
    void send_inputs(std::span<const scaleout::PlayerInput> inputs);
    void send_leaves(std::span<const std::uint32_t> entity_ids);

    [[nodiscard]] WorldFeedStats stats() const;

private:
    void on_tick_message(const scaleout::NatsMessage& message);
    void on_block_message(const scaleout::NatsMessage& message);
    /// Asks for a block when fewer than half a block are left and none was asked for
    /// within the last second.
    void maybe_reserve();
    void send(const std::string& what, const std::vector<std::byte>& bytes);

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
    std::uint64_t last_tick_ = 0;   ///< the newest tick accepted; older ones are refused
    std::deque<std::uint32_t> ids_; ///< reserved for us, not given out
    WorldFeedStats stats_;
    std::chrono::steady_clock::time_point last_reserve_{};
    bool reserve_pending_ = false;

    std::unique_ptr<scaleout::NatsSubscription> tick_sub_;
    std::unique_ptr<scaleout::NatsSubscription> block_sub_;
};

} // namespace dsoc::server
