// A gateway's feed of the world's ticks (WorldFeed) over a real nats-server (skipped,
// with the reason, where the binary is absent): a gateway that falls behind serves the
// newest tick and counts the ones it skipped; a tick that goes back in time, bad bytes
// and a tick of another world are refused and counted; ids come in blocks reserved by
// the world.

#include "dsoc/scaleout/world_process.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/world_feed.hpp"
#include "support/eventually.hpp"
#include "support/nats_server.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include <chrono>
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
    ServerConfig config;
    config.role = "gateway";
    config.nats_url = nats.url();
    config.world_name = "feed";
    config.bots = 5;
    const auto map = testing::rooms_map();
    scaleout::NatsLinkOptions options;
    options.url = nats.url();
    scaleout::NatsLink world_link(options);
    scaleout::WorldProcess world(map, world_settings(config), 30, world_link, "feed");

    boost::asio::io_context io; // not run: the ticks pile up as behind a busy gateway
    int posted = 0;
    WorldFeed feed(io, config, world.world_key(), [&] { ++posted; });
    ASSERT_TRUE(eventually([&] { return feed.stats().id_blocks == 1; })); // asked at start
    EXPECT_NE(feed.take_entity_id(), 0u);

    for (int i = 0; i < 3; ++i) {
        world.tick();
    }
    ASSERT_TRUE(eventually([&] { return feed.stats().ticks_received == 3; }));
    const auto newest = feed.take_newest();
    ASSERT_TRUE(newest.has_value());
    EXPECT_EQ(newest->tick, 3u);
    EXPECT_EQ(feed.stats().ticks_skipped, 2u);
    EXPECT_FALSE(feed.take_newest().has_value()); // nothing new since
    // One wake-up per arrival (the last may still be on its way to the queue).
    EXPECT_TRUE(eventually([&] {
        io.poll();
        io.restart();
        return posted == 3;
    })) << posted;

    // Bad bytes, another world's tick and a tick that goes back: refused, counted.
    std::vector<std::byte> bytes(10, std::byte{1});
    ASSERT_TRUE(world_link.publish("dsoc.feed.tick", bytes));
    scaleout::encode_world_tick(world.world(), world.world_key() + 1, 9, bytes);
    ASSERT_TRUE(world_link.publish("dsoc.feed.tick", bytes));
    scaleout::encode_world_tick(world.world(), world.world_key(), 2, bytes);
    ASSERT_TRUE(world_link.publish("dsoc.feed.tick", bytes));
    ASSERT_TRUE(eventually([&] { return feed.stats().bad_messages == 3; }));
    EXPECT_NE(feed.stats().last_error.find("world tick 2 after 3"), std::string::npos)
        << feed.stats().last_error;
    world.tick();
    ASSERT_TRUE(eventually([&] { return feed.stats().ticks_received == 4; }));
    EXPECT_EQ(feed.take_newest()->tick, 4u); // and the good ones still come
}

} // namespace
} // namespace dsoc::server
