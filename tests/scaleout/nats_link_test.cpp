// NatsLink against a real nats-server on loopback (skipped, with the reason, where
// the binary is absent; scripts/setup installs it): a world tick published is
// mirrored by a subscriber; a request is answered; the link comes back by itself
// after the server restarts; a subscriber that falls behind its pending limit drops
// and counts rather than queueing without end.

#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "support/eventually.hpp"
#include "support/nats_server.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace dsoc::scaleout {
namespace {

using namespace std::chrono_literals;
using testing::eventually;

class NatsLinkTest : public ::testing::Test {
protected:
    void SetUp() override {
        if (testing::nats_server_binary().empty()) {
            GTEST_SKIP() << testing::kNoNatsServer;
        }
        server_ = std::make_unique<testing::NatsServer>();
    }
    [[nodiscard]] NatsLinkOptions options(const std::string& name) const {
        NatsLinkOptions o;
        o.url = server_->url();
        o.name = name;
        o.reconnect_wait_ms = 50;
        return o;
    }
    std::unique_ptr<testing::NatsServer> server_;
};

TEST_F(NatsLinkTest, AWorldTickPublishedIsMirroredByASubscriber) {
    const auto map = testing::rooms_map();
    interest::WorldSettings settings;
    settings.bots = 30;
    interest::GameWorld world(settings, map);
    interest::GameWorld mirror(settings, map);
    const std::uint64_t key = world_key(*map, settings);

    NatsLink world_link(options("world"));
    NatsLink gateway_link(options("gateway"));
    std::mutex mutex;
    std::vector<WorldTick> received;
    std::vector<std::string> errors;
    const auto subscription =
        gateway_link.subscribe("dsoc.test.tick", [&](const NatsMessage& message) {
            auto tick = decode_world_tick(message.data, std::string(message.subject), key);
            const std::lock_guard lock(mutex);
            if (tick.ok()) {
                received.push_back(std::move(tick).value());
            } else {
                errors.push_back(tick.error().message());
            }
        });
    ASSERT_TRUE(gateway_link.flush(2000ms)); // the subscription is at the server

    std::vector<std::byte> bytes;
    for (std::uint64_t tick = 1; tick <= 10; ++tick) {
        world.step(1.0f / 30.0f);
        encode_world_tick(world, key, tick, bytes);
        ASSERT_TRUE(world_link.publish("dsoc.test.tick", bytes));
    }
    const std::vector<std::byte> garbage(17, std::byte{0x5a});
    ASSERT_TRUE(world_link.publish("dsoc.test.tick", garbage));
    ASSERT_TRUE(world_link.flush(2000ms));
    ASSERT_TRUE(eventually([&] {
        const std::lock_guard lock(mutex);
        return received.size() + errors.size() == 11;
    }));
    const std::lock_guard lock(mutex);
    ASSERT_EQ(received.size(), 10u);
    for (std::size_t i = 0; i < received.size(); ++i) {
        EXPECT_EQ(received[i].tick, i + 1); // in order, none lost
    }
    ASSERT_EQ(errors.size(), 1u); // garbage is refused with a reason naming the subject
    EXPECT_NE(errors[0].find("dsoc.test.tick"), std::string::npos) << errors[0];
    apply_world_tick(received.back(), mirror);
    std::vector<std::byte> again;
    encode_world_tick(mirror, key, 10, again);
    EXPECT_EQ(again, bytes); // the mirror is the world at tick 10
}

TEST_F(NatsLinkTest, ARequestIsAnswered) {
    NatsLink world_link(options("world"));
    NatsLink gateway_link(options("gateway"));
    const auto answering = world_link.subscribe("dsoc.test.join", [&](const NatsMessage& m) {
        std::vector<std::byte> reply(m.data.begin(), m.data.end());
        reply.push_back(std::byte{'!'});
        (void)world_link.publish(m.reply, reply);
    });
    ASSERT_TRUE(world_link.flush(2000ms));
    const std::vector<std::byte> ask{std::byte{'h'}, std::byte{'i'}};
    const auto reply = gateway_link.request("dsoc.test.join", ask, 2000ms);
    ASSERT_TRUE(reply.has_value());
    EXPECT_EQ(*reply, (std::vector<std::byte>{std::byte{'h'}, std::byte{'i'}, std::byte{'!'}}));
    EXPECT_FALSE(gateway_link.request("dsoc.test.nobody", ask, 200ms).has_value());
}

TEST_F(NatsLinkTest, TheLinkComesBackAfterTheServerRestarts) {
    NatsLink publisher(options("world"));
    NatsLink subscriber(options("gateway"));
    std::atomic<int> got{0};
    const auto subscription =
        subscriber.subscribe("dsoc.test.after", [&](const NatsMessage&) { ++got; });
    ASSERT_TRUE(subscriber.flush(2000ms));

    server_->stop();
    // The client's callbacks count, after the connection's state has changed.
    ASSERT_TRUE(eventually([&] {
        return publisher.disconnects() >= 1 && subscriber.disconnects() >= 1;
    })) << publisher.disconnects()
        << " " << subscriber.disconnects();
    EXPECT_FALSE(publisher.connected());
    server_->start(); // the same port
    ASSERT_TRUE(eventually([&] {
        return publisher.reconnects() >= 1 && subscriber.reconnects() >= 1;
    })) << publisher.reconnects()
        << " " << subscriber.reconnects();
    ASSERT_TRUE(subscriber.flush(2000ms)); // its subscription is back at the new server
    const std::vector<std::byte> one{std::byte{1}};
    ASSERT_TRUE(publisher.publish("dsoc.test.after", one));
    ASSERT_TRUE(publisher.flush(2000ms));
    EXPECT_TRUE(eventually([&] { return got.load() == 1; }));
}

TEST_F(NatsLinkTest, ASlowSubscriberDropsPastItsPendingLimit) {
    NatsLink publisher(options("world"));
    NatsLink subscriber(options("gateway"));
    std::mutex gate;
    gate.lock(); // the handler blocks on the first message until the burst is out
    std::atomic<int> handled{0};
    const auto subscription = subscriber.subscribe(
        "dsoc.test.burst",
        [&](const NatsMessage&) {
            const std::lock_guard lock(gate);
            ++handled;
        },
        4);
    ASSERT_TRUE(subscriber.flush(2000ms));
    const std::vector<std::byte> payload(100, std::byte{7});
    for (int i = 0; i < 50; ++i) {
        ASSERT_TRUE(publisher.publish("dsoc.test.burst", payload));
    }
    ASSERT_TRUE(publisher.flush(2000ms));
    // The whole burst reaches the client while the handler is blocked: one message in the
    // handler, at most the limit queued, the rest dropped. (Unlocking at the first drop
    // let the messages the client had not read yet through: 25-29 handled when the
    // client's reader lagged, under sanitizers or on one CPU.)
    ASSERT_TRUE(eventually([&] { return subscription->dropped() >= 50 - 1 - 4; }))
        << subscription->dropped();
    gate.unlock();
    ASSERT_TRUE(eventually([&] {
        return static_cast<std::uint64_t>(handled.load()) + subscription->dropped() == 50;
    }));
    EXPECT_LE(handled.load(), 1 + 4); // the one in the handler and the limit
}

} // namespace
} // namespace dsoc::scaleout
