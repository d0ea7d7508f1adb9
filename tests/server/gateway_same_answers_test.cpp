// The same answers through a gateway as from one process (docs/scale-out.md, "Why a
// client's answers are the single-process server's"): a world process (in this test, so
// that the test steps it and keeps every tick's authoritative world), a real nats-server
// and a real gateway (dsoc-server --role gateway's Server, on loopback) serving
// simulated players that move, fire and hear. The gateway's replication trace says, tick
// by tick, which entities each of its clients knew. The single-process server's
// per-client step (the dsoc policy's select, what the client hears, its own entity) is
// then run over the world's own state at each of those ticks, in the server's order,
// and must give every client exactly the set the gateway sent: the same answers tick
// after tick, though the policy's exact stages keep state from one tick to the next.

#include "dsoc/interest/hearing.hpp"
#include "dsoc/scaleout/world_process.hpp"
#include "dsoc/server/client_tick.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/server.hpp"
#include "dsoc/trace/trace_reader.hpp"
#include "integration/server_fixture.hpp"
#include "server/gateway_config.hpp"
#include "support/nats_server.hpp"
#include "support/temp_dir.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <set>
#include <thread>

namespace dsoc::server {
namespace {

using namespace std::chrono_literals;

std::vector<std::uint32_t> ids_of(const std::vector<interest::Interest>& set) {
    std::vector<std::uint32_t> out;
    for (const interest::Interest& i : set) {
        out.push_back(i.id);
    }
    return out;
}

TEST(GatewaySameAnswers, EveryClientGetsTheSingleProcessServersSetEveryTick) {
    if (testing::nats_server_binary().empty()) {
        GTEST_SKIP() << testing::kNoNatsServer;
    }
    testing::NatsServer nats;
    const testing::TempDir files("dsoc-gateway-same-answers");
    ServerConfig config = testing::gateway_config(nats.url(), "same");
    config.bots = 8;
    config.bot_shots_per_second = 2.0; // shots heard, deaths and respawns
    // The exact stages (as testing::RunningServer runs them; a baked table of this map takes
    // a minute to bake), with their hints and temporal coherence: answers that depend
    // on the ticks before.
    config.baked_stage = false;
    config.insecure = true;      // no connect tokens (as testing::RunningServer)
    config.culling_budget = 0.0; // no cheapest answers for a late tick: every set exact
    config.threads = 1;
    config.trace_file = files.path("gateway.jsonl");
    config.trace_every = 1;
    ASSERT_TRUE(config.sounds);
    ASSERT_TRUE(validate(config).empty());

    const auto map = testing::rooms_map();
    scaleout::NatsLinkOptions options;
    options.url = nats.url();
    scaleout::NatsLink world_link(options);
    scaleout::WorldProcess world(map, world_settings(config), config.tick_rate, world_link,
                                 config.world_name);
    ASSERT_TRUE(world_link.flush(2000ms)); // subscribed before the gateway asks for ids

    // The world's state after each of its ticks, kept to be judged after the run.
    std::map<std::uint64_t, interest::GameWorld> worlds;
    {
        testing::RunningServer gateway(config);
        simclient::LoadConfig lc;
        lc.transport = simclient::LoadConfig::Transport::tcp;
        lc.port = gateway.port();
        lc.clients = 4;
        lc.duration_s = 3.0;
        lc.ramp_up_s = 0.5;
        lc.progress = false;
        // The world ticks on a thread of its own at its rate, from before the first hello
        // (the gateway's ids are reserved by then) to after the last client has left.
        std::atomic<bool> running{true};
        std::thread ticking([&] {
            const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                std::chrono::duration<double>(1.0 / config.tick_rate));
            auto next = std::chrono::steady_clock::now();
            while (running.load()) {
                world.tick();
                worlds.emplace(world.stats().ticks, world.world());
                next += period;
                std::this_thread::sleep_until(next);
            }
        });
        std::this_thread::sleep_for(300ms);
        const simclient::LoadReport report = testing::run_load(lc);
        EXPECT_TRUE(report.passed()) << simclient::format_summary(report);
        std::this_thread::sleep_for(100ms); // the last tick served
        gateway.stop();
        running.store(false);
        ticking.join();
    }

    // The single-process server's step, over the world's own state at each traced tick.
    interest::GameWorld reference = worlds.begin()->second;
    const auto policy = make_policy(config, reference);
    interest::Hearing hearing;
    std::set<std::uint32_t> viewers; // every client seen, and those that left
    std::set<std::uint32_t> left;
    trace::TraceReader trace;
    ASSERT_TRUE(trace.open(config.trace_file)) << trace.error();
    trace::TraceTick t;
    std::size_t judged = 0;
    std::size_t heard = 0;
    std::size_t hidden = 0; // entities of the world a judged client was not sent
    while (trace.next(t)) {
        const auto state = worlds.find(t.t); // the gateway numbers ticks as the world does
        ASSERT_NE(state, worlds.end()) << "traced tick " << t.t << " was never published";
        reference = state->second;
        // As the server: a client's viewer is added when it says hello (its entity
        // spawned then), before the tick's begin_tick() (which meets that entity first),
        // and removed when it leaves.
        std::set<std::uint32_t> present;
        for (const trace::TraceClient& c : t.clients) {
            ASSERT_TRUE(c.entity.has_value()) << "tick " << t.t << " client " << c.id;
            present.insert(c.id);
            if (viewers.insert(c.id).second) {
                policy->add_viewer(c.id, *c.entity);
            }
        }
        for (const std::uint32_t gone : viewers) {
            if (!present.contains(gone) && !left.contains(gone)) {
                policy->remove_viewer(gone);
                left.insert(gone);
            }
        }
        policy->begin_tick(reference, t.t);
        hearing.begin_tick(reference);
        for (const trace::TraceClient& c : t.clients) {
            const interest::Entity* self = reference.find(*c.entity);
            ASSERT_NE(self, nullptr) << "tick " << t.t << " client " << c.id;
            const interest::Viewer viewer = interest::viewer_of(reference, c.id, *self);
            std::vector<interest::Interest> interest;
            policy->select(reference, viewer, interest);
            heard += hearing.add_heard(viewer, *policy, interest);
            add_own_entity(interest, *c.entity);
            ASSERT_EQ(ids_of(interest), c.replicated) << "tick " << t.t << " client " << c.id;
            hidden += reference.entities().size() - interest.size();
            ++judged;
        }
    }
    ASSERT_TRUE(trace.finished()) << trace.error();
    EXPECT_EQ(viewers.size(), 4u);
    EXPECT_GT(judged, 4u * 60u); // about 2.5 s of each client's ticks
    EXPECT_GT(heard, 0u);        // what a client hears is part of the answer compared
    EXPECT_GT(hidden, 0u);       // and the policy withholds something
}

} // namespace
} // namespace dsoc::server
