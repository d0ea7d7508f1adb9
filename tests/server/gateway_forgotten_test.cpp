// A real gateway (dsoc-server --role gateway's Server, on loopback) that its world
// process forgot (docs/scale-out.md, "Faults"): cut off from NATS past the world's
// timeout, taken for lost, its reserved ids given up to make room for another
// gateway's. Back again, its client's session ends with try_again after a bounded
// number of re-joins, and the client, connecting again, gets a fresh id and a player.

#include "dsoc/scaleout/world_process.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/server.hpp"
#include "integration/server_fixture.hpp"
#include "server/gateway_config.hpp"
#include "server/raw_client.hpp"
#include "support/eventually.hpp"
#include "support/nats_server.hpp"
#include "support/tcp_proxy.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace dsoc::server {
namespace {

using namespace std::chrono_literals;
using testing::eventually;

/// A Prometheus sample's value in `metrics`, or -1 when absent.
double sample(const std::string& metrics, const std::string& name) {
    const std::size_t at = metrics.find("\n" + name + " ");
    return at == std::string::npos ? -1.0 : std::stod(metrics.substr(at + name.size() + 2));
}

/// A raw TCP client whose session is open: it said hello and was not sent away.
struct Player {
    std::unique_ptr<testing::RawClient> client;
    /// Its Disconnect, once the server has closed the connection.
    std::future<std::optional<protocol::pb::Disconnect>> closed;
};

/// A client that says hello at `port` until it is not told to try again (a gateway
/// waiting for ids), within a few seconds.
Player connect(std::uint16_t port) {
    for (int attempt = 0; attempt < 20; ++attempt) {
        Player p{std::make_unique<testing::RawClient>(port), {}};
        p.client->send_message(testing::client_hello());
        p.closed =
            std::async(std::launch::async, [c = p.client.get()] { return c->read_until_closed(); });
        if (p.closed.wait_for(300ms) == std::future_status::timeout) {
            return p;
        }
        const auto refused = p.closed.get();
        EXPECT_TRUE(refused.has_value());
        if (!refused || refused->reason() != protocol::pb::DISCONNECT_REASON_TRY_AGAIN) {
            ADD_FAILURE() << (refused ? refused->text() : "closed without a reason");
            break;
        }
        std::this_thread::sleep_for(100ms);
    }
    ADD_FAILURE() << "no session";
    return {};
}

TEST(GatewayForgotten, ItsClientIsToldToTryAgainAndComesBackAsANewPlayer) {
    if (testing::nats_server_binary().empty()) {
        GTEST_SKIP() << testing::kNoNatsServer;
    }
    testing::NatsServer nats;
    testing::TcpProxy gateway_proxy(nats.port());
    ServerConfig config = testing::gateway_config(gateway_proxy.url(), "forgot");
    config.bots = 2;
    scaleout::NatsLinkOptions options;
    options.url = nats.url();
    scaleout::NatsLink world_link(options);
    scaleout::WorldProcess world(testing::rooms_map(), world_settings(config), config.tick_rate,
                                 world_link, "forgot", 500ms);
    ASSERT_TRUE(world_link.flush(2000ms));
    std::atomic<bool> running{true};
    std::thread ticking([&] {
        while (running.load()) {
            world.tick();
            std::this_thread::sleep_for(30ms);
        }
    });
    struct Stop {
        std::atomic<bool>& running;
        std::thread& thread;
        ~Stop() {
            running.store(false);
            thread.join();
        }
    } stop{running, ticking};

    Player first; // before the gateway, whose end closes their connections
    Player again;
    testing::RunningServer gateway(config);
    first = connect(gateway.port());
    ASSERT_TRUE(first.client);
    ASSERT_TRUE(eventually([&] { return world.stats().joins == 1; }));

    // Cut off past the world's timeout, and forgotten: another gateway reserves all the
    // room there is.
    gateway_proxy.cut();
    ASSERT_TRUE(eventually([&] { return world.stats().gateways_lost == 1; }));
    scaleout::NatsLink other(options);
    for (std::size_t reserved = 0; reserved < scaleout::WorldProcess::kMaxReserved;
         reserved += scaleout::kMaxIdBlock) {
        std::vector<std::byte> bytes;
        scaleout::encode_reserve_request({0x07e4, world.instance(), scaleout::kMaxIdBlock}, bytes);
        ASSERT_TRUE(other.request("dsoc.forgot.reserve", bytes, 2000ms).has_value());
    }
    ASSERT_EQ(world.stats().gateways_forgotten, 1u);
    gateway_proxy.restore();

    // Before, the session stayed on without its player, its join sent every second.
    ASSERT_EQ(first.closed.wait_for(15s), std::future_status::ready) << "the session never ended";
    const std::optional<protocol::pb::Disconnect> disconnect = first.closed.get();
    ASSERT_TRUE(disconnect.has_value());
    EXPECT_EQ(disconnect->reason(), protocol::pb::DISCONNECT_REASON_TRY_AGAIN);
    EXPECT_NE(disconnect->text().find("no longer holds"), std::string::npos) << disconnect->text();
    EXPECT_GE(world.stats().for_strangers, std::uint64_t{GatewayIds::kJoinResends});

    // The client connects again: a fresh id (the world forgets the other gateway, lost
    // too by now, to make room), and a player in the world.
    again = connect(gateway.port());
    ASSERT_TRUE(again.client);
    EXPECT_TRUE(eventually([&] { return world.stats().joins == 2; }));
    gateway.stop(); // the connection closes: its reader returns
    // Its hello is read once the reader has returned (the reader's thread writes it).
    ASSERT_EQ(again.closed.wait_for(15s), std::future_status::ready);
    EXPECT_GT(again.client->hello().entity_id(), first.client->hello().entity_id());
    const std::string metrics = gateway.render_metrics();
    EXPECT_EQ(sample(metrics, "dsoc_gateway_joins_abandoned_total"), 1.0) << metrics;
    // The rest of its first block (the hellos refused before it came asked for a few more).
    EXPECT_GE(sample(metrics, "dsoc_gateway_ids_voided_total"), GatewayIds::kIdBlock - 1.0)
        << metrics;
    EXPECT_NE(metrics.find("dsoc_disconnects_total{reason=\"try_again\"}"), std::string::npos)
        << metrics;
}

} // namespace
} // namespace dsoc::server
