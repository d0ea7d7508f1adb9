#include "dsoc/server/replication_state.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace dsoc::server {
namespace {

ServerConfig config_with_bots(int bots) {
    ServerConfig c;
    c.bots = bots;
    return c;
}

std::vector<std::uint32_t> ids(const google::protobuf::RepeatedField<std::uint32_t>& r) {
    return {r.begin(), r.end()};
}

TEST(ReplicationState, EnterThenUpdateThenLeave) {
    GameWorld world(config_with_bots(3), testing::rooms_map()); // ids 1, 2, 3
    ReplicationState state;
    protocol::pb::Snapshot snap;

    const std::vector<std::uint32_t> first = {1, 3};
    state.build_snapshot(world, first, 1, snap);
    ASSERT_EQ(snap.enter_size(), 2);
    EXPECT_EQ(snap.enter(0).id(), 1u);
    EXPECT_EQ(snap.enter(1).id(), 3u);
    EXPECT_EQ(snap.update_size(), 0);
    EXPECT_EQ(snap.leave_size(), 0);
    EXPECT_EQ(snap.server_tick(), 1u);

    // Nothing moved: no updates.
    state.build_snapshot(world, first, 2, snap);
    EXPECT_EQ(snap.enter_size() + snap.update_size() + snap.leave_size(), 0);

    world.step(0.1f); // bots move
    const std::vector<std::uint32_t> second = {2, 3};
    state.build_snapshot(world, second, 3, snap);
    ASSERT_EQ(snap.enter_size(), 1);
    EXPECT_EQ(snap.enter(0).id(), 2u);
    ASSERT_EQ(snap.update_size(), 1);
    EXPECT_EQ(snap.update(0).id(), 3u);
    EXPECT_EQ(ids(snap.leave()), std::vector<std::uint32_t>{1});
    EXPECT_EQ(state.known(), second);
}

TEST(ReplicationState, RemovedEntityLeaves) {
    GameWorld world(config_with_bots(2), testing::rooms_map());
    ReplicationState state;
    protocol::pb::Snapshot snap;
    const std::vector<std::uint32_t> both = {1, 2};
    state.build_snapshot(world, both, 1, snap);
    world.remove(2);
    const std::vector<std::uint32_t> one = {1};
    state.build_snapshot(world, one, 2, snap);
    EXPECT_EQ(ids(snap.leave()), std::vector<std::uint32_t>{2});
    EXPECT_EQ(state.known_count(), 1u);
}

TEST(ReplicationState, RandomSequencesKeepKnowledgeExact) {
    GameWorld world(config_with_bots(40), testing::rooms_map());
    ReplicationState state;
    protocol::pb::Snapshot snap;
    std::vector<std::uint32_t> client_view; // what a client applying the snapshots knows
    std::mt19937 rng(3);
    for (int tick = 1; tick <= 300; ++tick) {
        world.step(1.0f / 30.0f);
        std::vector<std::uint32_t> interest;
        for (std::uint32_t id = 1; id <= 40; ++id) {
            if (rng() % 3 == 0) {
                interest.push_back(id);
            }
        }
        state.build_snapshot(world, interest, static_cast<std::uint64_t>(tick), snap);
        for (const auto& e : snap.enter()) {
            ASSERT_EQ(std::count(client_view.begin(), client_view.end(), e.id()), 0);
            client_view.push_back(e.id());
        }
        for (const auto& u : snap.update()) {
            ASSERT_EQ(std::count(client_view.begin(), client_view.end(), u.id()), 1);
        }
        for (const auto id : snap.leave()) {
            const auto it = std::find(client_view.begin(), client_view.end(), id);
            ASSERT_NE(it, client_view.end());
            client_view.erase(it);
        }
        std::sort(client_view.begin(), client_view.end());
        ASSERT_EQ(client_view, interest) << "tick " << tick;
    }
}

} // namespace
} // namespace dsoc::server
