// A gateway's feed of the world's ticks (WorldFeed) over a real nats-server (skipped,
// with the reason, where the binary is absent): a gateway that falls behind serves the
// newest tick and counts the ones it skipped; a tick that goes back in time, or jumps
// further ahead than the world's clock allows, bad bytes and a tick of another world are
// refused and counted; ids come in blocks reserved by the world instance the gateway
// follows, asked of it alone (of two world processes on one name, the other reserves
// nothing). And the faults it repairs, each made for real by cutting one process's
// connection to NATS (a TCP proxy between it and the server): a join or a leave lost
// while the world was cut off is sent again until the ticks show it taken; a world
// process replaced by a new one is followed from its own tick 1 (fresh ids for all its
// players asked for at once; a stray first tick numbered near 2^64 is refused); a
// second world on the same name takes none of a gateway's messages; a gateway the world
// took for lost gets its players back once it is heard again, and one it forgot gives
// its players' joins up and asks for fresh ids; a tick forged ahead with a clock to
// match is got over.

#include "dsoc/scaleout/world_process.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/world_feed.hpp"
#include "server/gateway_config.hpp"
#include "support/eventually.hpp"
#include "support/nats_server.hpp"
#include "support/tcp_proxy.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <span>
#include <thread>

namespace dsoc::server {
namespace {

using namespace std::chrono_literals;
using testing::eventually;

TEST(WorldFeed, AGatewayBehindServesTheNewestTickAndCountsTheRest) {
    if (testing::nats_server_binary().empty()) {
        GTEST_SKIP() << testing::kNoNatsServer;
    }
    testing::NatsServer nats;
    ServerConfig config = testing::gateway_config(nats.url(), "feed");
    config.bots = 5;
    const auto map = testing::rooms_map();
    scaleout::NatsLinkOptions options;
    options.url = nats.url();
    scaleout::NatsLink world_link(options);
    scaleout::WorldProcess world(map, world_settings(config), 30, world_link, "feed");
    ASSERT_TRUE(world_link.flush(2000ms)); // subscribed before the feed asks for ids

    boost::asio::io_context io; // not run: the ticks pile up as behind a busy gateway
    int posted = 0;
    WorldFeed feed(io, config, world.world_key(), [&] { ++posted; });
    // Ticks until one comes after the feed's subscription is in: followed, ids asked of it
    // at once.
    ASSERT_TRUE(eventually([&] {
        world.tick();
        return feed.stats().ticks_received > 0;
    }));
    ASSERT_TRUE(eventually([&] { return feed.stats().id_blocks == 1; }));
    EXPECT_NE(feed.take_entity_id(), 0u);
    std::this_thread::sleep_for(100ms); // every tick on its way arrived
    ASSERT_TRUE(feed.take_newest().has_value());
    const WorldFeedStats before = feed.stats();

    for (int i = 0; i < 3; ++i) {
        world.tick();
    }
    ASSERT_TRUE(
        eventually([&] { return feed.stats().ticks_received == before.ticks_received + 3; }));
    const auto newest = feed.take_newest();
    ASSERT_TRUE(newest.has_value());
    const std::uint64_t last = world.stats().ticks;
    EXPECT_EQ(newest->tick.tick, last);
    EXPECT_EQ(newest->number, last); // the first world this gateway follows: its numbers
    EXPECT_FALSE(newest->restart.has_value());
    EXPECT_EQ(feed.stats().ticks_skipped, before.ticks_skipped + 2);
    EXPECT_FALSE(feed.take_newest().has_value()); // nothing new since
    // One wake-up per arrival (the last may still be on its way to the queue).
    EXPECT_TRUE(eventually([&] {
        io.poll();
        io.restart();
        return posted == static_cast<int>(before.ticks_received + 3);
    })) << posted;

    // Bad bytes, another world's tick and a tick that goes back: refused, counted.
    std::vector<std::byte> bytes(10, std::byte{1});
    ASSERT_TRUE(world_link.publish("dsoc.feed.tick", bytes));
    scaleout::encode_world_tick(world.world(), world.world_key() + 1, 9, bytes);
    ASSERT_TRUE(world_link.publish("dsoc.feed.tick", bytes));
    scaleout::encode_world_tick(world.world(), world.world_key(), 2, bytes, 0, world.instance());
    ASSERT_TRUE(world_link.publish("dsoc.feed.tick", bytes));
    ASSERT_TRUE(eventually([&] { return feed.stats().bad_messages == 3; }));
    EXPECT_NE(
        feed.stats().last_error.find("dsoc.feed.tick: world tick 2 after " + std::to_string(last)),
        std::string::npos)
        << feed.stats().last_error;
    world.tick();
    ASSERT_TRUE(
        eventually([&] { return feed.stats().ticks_received == before.ticks_received + 4; }));
    EXPECT_EQ(feed.take_newest()->tick.tick, last + 1); // and the good ones still come
}

TEST(WorldFeed, ARefusedIdBlockLeavesItsRequestPending) {
    if (testing::nats_server_binary().empty()) {
        GTEST_SKIP() << testing::kNoNatsServer;
    }
    testing::NatsServer nats;
    ServerConfig config = testing::gateway_config(nats.url(), "refused");
    scaleout::NatsLinkOptions options;
    options.url = nats.url();
    scaleout::NatsLink fake_world(options); // answers nothing but what the test says
    std::mutex mutex;
    std::vector<scaleout::ReserveRequest> requests;
    std::string reply;
    const auto sub =
        fake_world.subscribe("dsoc.refused.reserve", [&](const scaleout::NatsMessage& m) {
            auto request = scaleout::decode_reserve_request(m.data, "reserve");
            ASSERT_TRUE(request.ok()) << request.error().message();
            const std::lock_guard lock(mutex);
            requests.push_back(request.value());
            reply = std::string(m.reply);
        });
    ASSERT_TRUE(fake_world.flush(2000ms));
    const auto count = [&] {
        const std::lock_guard lock(mutex);
        return requests.size();
    };

    boost::asio::io_context io;
    WorldFeed feed(io, config, 42, [] {});
    // Nothing asked before a world's tick says which instance to ask.
    std::this_thread::sleep_for(200ms);
    EXPECT_EQ(count(), 0u);
    std::string why;
    EXPECT_EQ(feed.take_entity_id(&why), 0u);
    EXPECT_NE(why.find("no world tick yet"), std::string::npos) << why;
    const interest::GameWorld world(world_settings(config), testing::rooms_map());
    std::vector<std::byte> bytes;
    std::uint64_t tick = 0;
    ASSERT_TRUE(eventually([&] { // until one comes after the feed's subscription is in
        scaleout::encode_world_tick(world, 42, ++tick, bytes, 0, 7); // of instance 7
        EXPECT_TRUE(fake_world.publish("dsoc.refused.tick", bytes));
        return count() == 1;
    }));
    const auto asked = std::chrono::steady_clock::now();
    {
        const std::lock_guard lock(mutex);
        EXPECT_EQ(requests[0].instance, 7u);                    // the instance followed
        EXPECT_EQ(requests[0].count, GatewayIds::kIdBlock + 1); // and the hello refused
    }
    scaleout::encode_id_block({43, 7, 1, 10}, bytes); // of another world: refused
    ASSERT_TRUE(fake_world.publish(reply, bytes));
    ASSERT_TRUE(eventually([&] { return feed.stats().bad_messages == 1; }));
    scaleout::encode_id_block({42, 8, 1, 10}, bytes); // of an instance not followed
    ASSERT_TRUE(fake_world.publish(reply, bytes));
    ASSERT_TRUE(eventually([&] { return feed.stats().other_instance == 1; }));
    EXPECT_EQ(feed.stats().id_blocks, 0u);

    // Still pending: a hello does not send another request before the retry is due.
    EXPECT_EQ(feed.take_entity_id(), 0u);
    std::this_thread::sleep_for(200ms);
    EXPECT_EQ(count(), 1u);
    std::this_thread::sleep_until(asked + 1100ms);
    EXPECT_EQ(feed.take_entity_id(), 0u);
    EXPECT_TRUE(eventually([&] { return count() == 2; })); // the retry
}

TEST(WorldFeed, OfTwoWorldsOnOneNameTheGatewayTakesIdsOfTheOneItFollowsAlone) {
    if (testing::nats_server_binary().empty()) {
        GTEST_SKIP() << testing::kNoNatsServer;
    }
    // Two world processes on one name (a standby started before the old one is stopped),
    // both live before the gateway starts.
    testing::NatsServer nats;
    ServerConfig config = testing::gateway_config(nats.url(), "two");
    const auto map = testing::rooms_map();
    scaleout::NatsLinkOptions options;
    options.url = nats.url();
    scaleout::NatsLink first_link(options);
    scaleout::NatsLink second_link(options);
    scaleout::WorldProcess first(map, world_settings(config), 30, first_link, "two");
    scaleout::WorldProcess second(map, world_settings(config), 30, second_link, "two");
    ASSERT_TRUE(first_link.flush(2000ms));
    ASSERT_TRUE(second_link.flush(2000ms));

    boost::asio::io_context io;
    WorldFeed feed(io, config, first.world_key(), [] {});
    ASSERT_TRUE(eventually([&] { // heard first: followed
        first.tick();
        return feed.stats().id_blocks == 1;
    }));
    // The gateway asked the first alone: the second reserved nothing (before, a first
    // request named no instance and both answered; the second kept its block for a
    // gateway it never heard again, and took that gateway for lost).
    ASSERT_TRUE(eventually([&] { return second.messages_received() == 1; })); // the request
    EXPECT_EQ(second.stats().ids_reserved, 0u);
    EXPECT_EQ(second.stats().other_instance, 1u);
    EXPECT_EQ(first.stats().ids_reserved, feed.stats().ids_left);

    // Both tick on; the gateway keeps to the first, and asks it alone for more ids.
    std::size_t given = 0;
    for (int i = 0; i < 40; ++i) {
        first.tick();
        second.tick();
        std::vector<std::uint32_t> players;
        for (int n = 0; n < 10; ++n) {
            if (const std::uint32_t id = feed.take_entity_id(); id != 0) {
                players.push_back(id);
            }
        }
        given += players.size();
        if (const auto taken = feed.take_newest()) {
            EXPECT_EQ(taken->tick.instance, first.instance());
            EXPECT_FALSE(taken->restart.has_value());
        }
        feed.send_joins(players);
        feed.send_inputs({});
        std::this_thread::sleep_for(30ms);
    }
    ASSERT_GT(given, std::size_t{GatewayIds::kIdBlock}); // more than one block
    ASSERT_TRUE(eventually([&] { return first.stats().joins == given; }));
    EXPECT_GE(feed.stats().id_blocks, 2u);
    EXPECT_EQ(first.stats().ids_reserved, given + feed.stats().ids_left); // all of the first's
    std::this_thread::sleep_for(100ms); // what is on its way to the second arrived
    const scaleout::WorldProcessStats other = second.stats();
    EXPECT_EQ(other.ids_reserved, 0u);
    EXPECT_EQ(other.joins + other.inputs + other.for_strangers + other.gateways_lost, 0u);
    EXPECT_EQ(other.other_instance, second.messages_received());
    EXPECT_GE(feed.stats().other_instance, 40u); // the second's ticks
    EXPECT_EQ(feed.stats().world_restarts, 0u);
    EXPECT_EQ(feed.stats().bad_messages, 0u);
}

/// A world process and one gateway's feed on a real nats-server, each through a proxy
/// that can cut it off.
class WorldFeedFaults : public ::testing::Test {
protected:
    void SetUp() override {
        if (testing::nats_server_binary().empty()) {
            GTEST_SKIP() << testing::kNoNatsServer;
        }
        nats_ = std::make_unique<testing::NatsServer>();
        world_proxy_ = std::make_unique<testing::TcpProxy>(nats_->port());
        gateway_proxy_ = std::make_unique<testing::TcpProxy>(nats_->port());
        config_ = testing::gateway_config(gateway_proxy_->url(), "faults");
        config_.bots = 3;
        scaleout::NatsLinkOptions options;
        options.url = world_proxy_->url();
        world_link_ = std::make_unique<scaleout::NatsLink>(options);
        start_world();
        feed_ = std::make_unique<WorldFeed>(io_, config_, world_->world_key(), [] {});
        // The feed follows the world (from a tick that comes after its subscription is
        // in), and asks it for ids.
        ASSERT_TRUE(step_until([](const scaleout::WorldTick&) { return true; }));
        ASSERT_TRUE(eventually([&] { return feed_->stats().id_blocks == 1; }));
    }
    void TearDown() override {
        feed_.reset();
        world_.reset();
    }
    [[nodiscard]] virtual std::chrono::milliseconds gateway_timeout() const {
        return scaleout::WorldProcess::kDefaultGatewayTimeout;
    }
    /// A world process (a new instance each time) on the world's link.
    void start_world() {
        world_.reset(); // unsubscribes first
        world_ =
            std::make_unique<scaleout::WorldProcess>(testing::rooms_map(), world_settings(config_),
                                                     30, *world_link_, "faults", gateway_timeout());
        ASSERT_TRUE(world_link_->flush(2000ms));
    }
    /// One world step and one gateway tick, as a gateway runs them: the world steps and
    /// publishes; the feed takes the tick (re-sending what it shows lost) and sends its
    /// heartbeat. Nothing when the tick does not arrive within a second.
    std::optional<TakenTick> step() {
        const std::uint64_t before = feed_->stats().ticks_received;
        world_->tick();
        if (!eventually([&] { return feed_->stats().ticks_received > before; }, 1s)) {
            return std::nullopt;
        }
        auto taken = feed_->take_newest();
        feed_->send_inputs({});
        return taken;
    }
    /// Steps about 30 times a second until a taken tick satisfies `done`; false after
    /// `timeout`.
    template <typename F>
    bool step_until(F done, std::chrono::milliseconds timeout = 5s) {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < deadline) {
            if (const auto taken = step(); taken && done(taken->tick)) {
                return true;
            }
            std::this_thread::sleep_for(30ms);
        }
        return false;
    }
    static bool has(const scaleout::WorldTick& tick, std::uint32_t id) {
        return std::any_of(tick.entities.begin(), tick.entities.end(),
                           [&](const interest::Entity& e) { return e.id == id; });
    }
    /// A new player of the gateway's, joined and seen in a tick.
    std::uint32_t joined_player() {
        const std::uint32_t id = feed_->take_entity_id();
        EXPECT_NE(id, 0u);
        feed_->send_joins(std::span(&id, 1));
        EXPECT_TRUE(step_until([&](const scaleout::WorldTick& t) { return has(t, id); }));
        return id;
    }
    /// Cuts the world process off NATS, runs `meanwhile`, and lets it back.
    template <typename F>
    void with_world_cut_off(F meanwhile) {
        world_proxy_->cut();
        ASSERT_TRUE(eventually([&] { return !world_link_->connected(); }));
        meanwhile();
        std::this_thread::sleep_for(200ms); // delivered to no one by now
        world_proxy_->restore();
        ASSERT_TRUE(eventually([&] { return world_link_->connected(); }));
        ASSERT_TRUE(world_link_->flush(2000ms)); // subscribed again
    }

    std::unique_ptr<testing::NatsServer> nats_;
    std::unique_ptr<testing::TcpProxy> world_proxy_;
    std::unique_ptr<testing::TcpProxy> gateway_proxy_;
    ServerConfig config_;
    std::unique_ptr<scaleout::NatsLink> world_link_;
    std::unique_ptr<scaleout::WorldProcess> world_;
    boost::asio::io_context io_; // not run: the tests take the ticks themselves
    std::unique_ptr<WorldFeed> feed_;
};

TEST_F(WorldFeedFaults, AJoinLostWhileTheWorldWasCutOffIsSentAgain) {
    const std::uint32_t id = feed_->take_entity_id();
    ASSERT_NE(id, 0u);
    // Published while no world is subscribed: NATS drops it.
    with_world_cut_off([&] { feed_->send_joins(std::span(&id, 1)); });
    EXPECT_TRUE(step_until([&](const scaleout::WorldTick& t) { return has(t, id); }))
        << "the player never spawned";
    EXPECT_EQ(feed_->stats().joins_resent, 1u);
    EXPECT_EQ(world_->stats().joins, 1u);
    EXPECT_EQ(world_->stats().for_strangers, 0u);
}

TEST_F(WorldFeedFaults, ALeaveLostWhileTheWorldWasCutOffIsSentAgain) {
    const std::uint32_t id = joined_player();
    with_world_cut_off([&] { feed_->send_leaves(std::span(&id, 1)); });
    EXPECT_TRUE(step_until([&](const scaleout::WorldTick& t) { return !has(t, id); }))
        << "a ghost stays";
    EXPECT_EQ(feed_->stats().leaves_resent, 1u);
    EXPECT_EQ(world_->stats().leaves, 1u);
    EXPECT_EQ(feed_->stats().joins_resent, 0u); // nothing else was sent again
}

TEST_F(WorldFeedFaults, ARestartedWorldIsFollowedFromItsFirstTick) {
    for (int i = 0; i < 5; ++i) {
        ASSERT_TRUE(step().has_value());
    }
    const std::uint32_t id = joined_player();
    const std::uint64_t old_instance = world_->instance();
    start_world(); // the world process restarted: its ticks count from 1 again

    // While the old instance may be live (a second world process on the same name),
    // the new one is not followed.
    world_->tick();
    ASSERT_TRUE(eventually([&] { return feed_->stats().other_instance == 1; }));
    std::this_thread::sleep_for(WorldFeed::kWorldSilence);
    // Before, this tick was refused as going back in time, and every later one too.
    const std::uint64_t ticks = feed_->stats().ticks_received;
    world_->tick();
    ASSERT_TRUE(eventually([&] { return feed_->stats().ticks_received == ticks + 1; }))
        << feed_->stats().last_error;
    // The feed follows the new world; the server has not taken the restart yet: a hello
    // is told to try again, and inputs of the old world's sessions name the old world
    // (the new one drops them, whatever entity the id is there: here a bot).
    std::string why;
    EXPECT_EQ(feed_->take_entity_id(&why), 0u);
    EXPECT_NE(why.find("restarted"), std::string::npos) << why;
    const std::uint64_t other = world_->stats().other_instance;
    const scaleout::PlayerInput old_input{1, glm::vec3(1.0f, 0.0f, 0.0f), false, true, 0, 0};
    feed_->send_inputs(std::span(&old_input, 1));
    ASSERT_TRUE(eventually([&] { return world_->stats().other_instance > other; }));
    EXPECT_EQ(world_->stats().inputs + world_->stats().for_strangers, 0u);
    auto taken = feed_->take_newest();
    feed_->send_inputs({});
    ASSERT_TRUE(taken.has_value()) << feed_->stats().last_error;
    EXPECT_EQ(taken->tick.tick, 2u);
    ASSERT_TRUE(taken->restart.has_value());
    EXPECT_EQ(taken->restart->old_instance, old_instance);
    EXPECT_EQ(taken->restart->new_instance, world_->instance());
    EXPECT_EQ(feed_->stats().world_restarts, 1u);
    EXPECT_EQ(feed_->stats().bad_messages, 0u);
    EXPECT_FALSE(has(taken->tick, id)); // and the old world's players are not re-joined
    ASSERT_TRUE(eventually([&] { return feed_->stats().id_blocks == 2; })); // fresh ids

    // The new world hands this gateway the same numbers again: a leave of the old
    // world's player is void (sent, it would release the new block's first id), and the
    // same number joins a new player.
    feed_->send_leaves(std::span(&id, 1));
    EXPECT_EQ(joined_player(), id);
    EXPECT_EQ(world_->stats().for_strangers, 0u);

    // The old instance's ticks are refused while the new one is live, whatever their
    // number.
    std::vector<std::byte> bytes;
    scaleout::encode_world_tick(world_->world(), world_->world_key(), 1000, bytes, 0, old_instance);
    ASSERT_TRUE(world_link_->publish("dsoc.faults.tick", bytes));
    ASSERT_TRUE(eventually([&] { return feed_->stats().other_instance == 2; }));
    const auto next = step();
    ASSERT_TRUE(next.has_value());
    EXPECT_FALSE(next->restart.has_value());
    EXPECT_EQ(feed_->stats().world_restarts, 1u);
    EXPECT_EQ(feed_->stats().bad_messages, 0u);
}

TEST_F(WorldFeedFaults, AfterARestartOneRequestCoversEveryPlayerThatWasThere) {
    // 600 clients on this gateway (more than two blocks of ids).
    constexpr std::size_t kPlayers = 600;
    std::size_t players = 0;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (players < kPlayers && std::chrono::steady_clock::now() < deadline) {
        if (feed_->take_entity_id() != 0) {
            ++players;
        } else {
            std::this_thread::sleep_for(5ms); // a block on its way
        }
    }
    ASSERT_EQ(players, kPlayers);
    const std::uint64_t blocks = feed_->stats().id_blocks;
    start_world();
    world_->tick();
    ASSERT_TRUE(eventually([&] { return feed_->stats().other_instance == 1; }));
    std::this_thread::sleep_for(WorldFeed::kWorldSilence);
    world_->tick(); // followed: their sessions end, and their clients come back together

    // Asked for at once (no hello, no gateway tick needed), in one request: before, one
    // block of 256, and the rest of the clients refused until more came.
    ASSERT_TRUE(eventually([&] { return feed_->stats().id_blocks == blocks + 1; }));
    EXPECT_GE(feed_->stats().ids_left, kPlayers);
    EXPECT_EQ(world_->stats().ids_reserved, feed_->stats().ids_left);
    ASSERT_TRUE(feed_->take_newest()->restart.has_value());
    EXPECT_NE(feed_->take_entity_id(), 0u);
}

TEST_F(WorldFeedFaults, ASecondWorldOnTheSameNameTakesNothingOfTheGateways) {
    scaleout::WorldProcess second(testing::rooms_map(), world_settings(config_), 30, *world_link_,
                                  "faults");
    ASSERT_TRUE(world_link_->flush(2000ms));
    // Enough new players for a reserve request, their joins, an input and a leave.
    std::vector<std::uint32_t> players;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (players.size() < GatewayIds::kIdBlock && std::chrono::steady_clock::now() < deadline) {
        if (const std::uint32_t id = feed_->take_entity_id(); id != 0) {
            players.push_back(id);
        } else {
            std::this_thread::sleep_for(5ms);
        }
    }
    ASSERT_EQ(players.size(), GatewayIds::kIdBlock);
    ASSERT_TRUE(eventually([&] { return feed_->stats().id_blocks == 2; }));
    feed_->send_joins(players);
    ASSERT_TRUE(step_until([&](const scaleout::WorldTick& t) { return has(t, players.back()); }));
    const scaleout::PlayerInput input{players[0], glm::vec3(1.0f, 0.0f, 0.0f), true, true, 0, 0};
    feed_->send_inputs(std::span(&input, 1));
    feed_->send_leaves(std::span(players).first(1));
    ASSERT_TRUE(step_until([&](const scaleout::WorldTick& t) { return !has(t, players[0]); }));

    // The second world heard all of it (on the same connection as the first), and took
    // none.
    std::this_thread::sleep_for(100ms);
    const scaleout::WorldProcessStats stats = second.stats();
    EXPECT_GE(stats.other_instance, 4u); // a reserve request, joins, inputs, a leave
    EXPECT_EQ(stats.other_instance, second.messages_received());
    EXPECT_EQ(stats.ids_reserved, 0u);
    EXPECT_EQ(stats.joins + stats.leaves + stats.inputs + stats.for_strangers, 0u);
    EXPECT_EQ(world_->stats().joins, GatewayIds::kIdBlock);
    EXPECT_EQ(world_->stats().leaves, 1u);
    EXPECT_EQ(feed_->stats().other_instance, 0u); // and no block of the second's came
}

TEST_F(WorldFeedFaults, AnImplausibleFirstTickTakesNoGatewayOver) {
    std::this_thread::sleep_for(WorldFeed::kWorldSilence); // the world followed is silent
    std::vector<std::byte> bytes;
    scaleout::encode_world_tick(world_->world(), world_->world_key(), WorldFeed::kMaxFirstTick + 1,
                                bytes, 0, world_->instance() ^ 1);
    ASSERT_TRUE(world_link_->publish("dsoc.faults.tick", bytes));
    ASSERT_TRUE(eventually([&] { return feed_->stats().bad_messages == 1; }));
    EXPECT_NE(feed_->stats().last_error.find("as the first of instance"), std::string::npos)
        << feed_->stats().last_error;
    const auto next = step(); // the world followed, heard again
    ASSERT_TRUE(next.has_value());
    EXPECT_FALSE(next->restart.has_value());
    EXPECT_EQ(feed_->stats().world_restarts, 0u);
}

TEST_F(WorldFeedFaults, ATickFarAheadOfTheWorldsClockIsRefusedAndTheNextIsServed) {
    const auto last = step();
    ASSERT_TRUE(last.has_value());
    const auto forge = [&](std::uint64_t number, std::uint64_t published) {
        std::vector<std::byte> bytes;
        scaleout::encode_world_tick(world_->world(), world_->world_key(), number, bytes, published,
                                    world_->instance());
        ASSERT_TRUE(world_link_->publish("dsoc.faults.tick", bytes));
    };
    // Of the instance followed, numbered 2^64 - 1, stamped now; then stamped 2^64 - 1 ns
    // too (585 years of the world's clock are still not enough steps): both refused.
    // Before, the first was taken, and every tick after it refused as not newer.
    forge(UINT64_MAX, scaleout::monotonic_ns());
    ASSERT_TRUE(eventually([&] { return feed_->stats().bad_messages == 1; }));
    EXPECT_NE(feed_->stats().last_error.find("ticks ahead in"), std::string::npos)
        << feed_->stats().last_error;
    forge(UINT64_MAX, UINT64_MAX);
    ASSERT_TRUE(eventually([&] { return feed_->stats().bad_messages == 2; }));
    auto next = step();
    ASSERT_TRUE(next.has_value()) << feed_->stats().last_error;
    EXPECT_EQ(next->tick.tick, last->tick.tick + 1);
    EXPECT_EQ(next->number, last->number + 1);

    // One forged with a publish time to match (a second of the world's clock ahead for
    // each 240 ticks) is taken: the world's own ticks are then behind it, refused, until
    // they have gone back for WorldFeed::kWorldSilence; then the instance is followed anew
    // and the gateway's numbers go on increasing.
    const std::uint64_t ahead = 10 * kMaxTickRate;
    const std::uint64_t received = feed_->stats().ticks_received;
    forge(next->tick.tick + ahead, next->tick.published_ns + 10'000'000'000);
    ASSERT_TRUE(eventually([&] { return feed_->stats().ticks_received == received + 1; }));
    const auto forged = feed_->take_newest();
    ASSERT_TRUE(forged.has_value());
    EXPECT_EQ(forged->number, next->number + ahead);
    world_->tick();
    ASSERT_TRUE(eventually([&] { return feed_->stats().bad_messages == 3; }));
    EXPECT_NE(feed_->stats().last_error.find("not newer"), std::string::npos)
        << feed_->stats().last_error;
    EXPECT_TRUE(step_until([](const scaleout::WorldTick&) { return true; }, 3s))
        << feed_->stats().last_error;
    EXPECT_EQ(feed_->stats().world_resyncs, 1u);
    next = step();
    ASSERT_TRUE(next.has_value());
    EXPECT_GT(next->number, forged->number);
    EXPECT_EQ(feed_->stats().world_restarts, 0u);
}

class WorldFeedShortTimeout : public WorldFeedFaults {
protected:
    [[nodiscard]] std::chrono::milliseconds gateway_timeout() const override { return 500ms; }
};

TEST_F(WorldFeedShortTimeout, AGatewayTheWorldTookForLostGetsItsPlayersBack) {
    const std::uint32_t id = joined_player();
    gateway_proxy_->cut();
    ASSERT_TRUE(eventually([&] { return feed_->stats().nats_disconnects == 1; }));
    for (int i = 0; i < 30; ++i) { // a second of steps the gateway does not see
        world_->tick();
        std::this_thread::sleep_for(30ms);
    }
    EXPECT_EQ(world_->stats().gateways_lost, 1u);
    EXPECT_EQ(world_->world().find(id), nullptr);
    gateway_proxy_->restore();
    ASSERT_TRUE(eventually([&] { return feed_->stats().nats_reconnects == 1; }));

    // Before, the world refused the re-join (not reserved): the client kept a session
    // without its entity.
    EXPECT_TRUE(step_until([&](const scaleout::WorldTick& t) { return has(t, id); }))
        << "the player never came back";
    EXPECT_EQ(world_->stats().gateways_back, 1u);
    EXPECT_EQ(feed_->stats().joins_resent, 1u);
    EXPECT_EQ(world_->stats().for_strangers, 0u);
}

TEST_F(WorldFeedShortTimeout, AGatewayTheWorldForgotGivesUpItsJoinsAndAsksForFreshIds) {
    const std::uint32_t id = joined_player();
    gateway_proxy_->cut();
    ASSERT_TRUE(eventually([&] { return feed_->stats().nats_disconnects == 1; }));
    ASSERT_TRUE(eventually([&] {
        world_->tick();
        std::this_thread::sleep_for(30ms);
        return world_->stats().gateways_lost == 1;
    }));
    // Another gateway reserves all the room there is: the world forgets the lost one.
    scaleout::NatsLinkOptions options;
    options.url = nats_->url();
    scaleout::NatsLink other(options);
    for (std::size_t reserved = 0; reserved < scaleout::WorldProcess::kMaxReserved;
         reserved += scaleout::kMaxIdBlock) {
        std::vector<std::byte> bytes;
        scaleout::encode_reserve_request({0x07e4, world_->instance(), scaleout::kMaxIdBlock},
                                         bytes);
        ASSERT_TRUE(other.request("dsoc.faults.reserve", bytes, 2000ms).has_value());
    }
    ASSERT_EQ(world_->stats().gateways_forgotten, 1u);
    gateway_proxy_->restore();
    ASSERT_TRUE(eventually([&] { return feed_->stats().nats_reconnects == 1; }));

    // Its re-joins are refused (the id is not reserved for it any more), a bounded number
    // of times; then the join is given up, its session to be ended, and the rest of its
    // block dropped. Before, the join was sent again every second, for good.
    std::optional<TakenTick> abandoned;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (!abandoned && std::chrono::steady_clock::now() < deadline) {
        if (auto taken = step(); taken && !taken->abandoned.empty()) {
            abandoned = std::move(taken);
        }
        std::this_thread::sleep_for(30ms);
    }
    ASSERT_TRUE(abandoned.has_value()) << "the join was never given up";
    EXPECT_EQ(abandoned->abandoned, std::vector<std::uint32_t>{id});
    const WorldFeedStats stats = feed_->stats();
    EXPECT_EQ(stats.joins_resent, std::uint64_t{GatewayIds::kJoinResends});
    EXPECT_EQ(stats.joins_abandoned, 1u);
    EXPECT_EQ(stats.ids_voided, GatewayIds::kIdBlock - 1);
    EXPECT_GE(world_->stats().for_strangers, std::uint64_t{GatewayIds::kJoinResends});
    for (int i = 0; i < 30; ++i) { // nothing more is sent for it
        (void)step();
        std::this_thread::sleep_for(50ms);
    }
    EXPECT_EQ(feed_->stats().joins_resent, stats.joins_resent);

    // Its client connects again: fresh ids (the world forgets the other gateway, lost
    // too by now, to make room), and the new player joins.
    std::uint32_t fresh = 0;
    ASSERT_TRUE(eventually([&] {
        fresh = feed_->take_entity_id();
        return fresh != 0;
    }));
    EXPECT_GT(fresh, id);
    feed_->send_joins(std::span(&fresh, 1));
    EXPECT_TRUE(step_until([&](const scaleout::WorldTick& t) { return has(t, fresh); }))
        << "the new player never joined";
    EXPECT_EQ(feed_->stats().id_blocks, 2u);
}

} // namespace
} // namespace dsoc::server
