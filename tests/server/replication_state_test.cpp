#include "dsoc/protocol/acked_snapshot.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/datagram.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/replication_state.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
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

std::vector<interest::Interest> near(std::initializer_list<std::uint32_t> list) {
    std::vector<interest::Interest> out;
    for (const auto id : list) {
        out.push_back({id, 0});
    }
    return out;
}

std::vector<std::uint32_t> id_list(const std::vector<interest::Interest>& set) {
    std::vector<std::uint32_t> out;
    for (const auto& i : set) {
        out.push_back(i.id);
    }
    return out;
}

/// The ids of a snapshot's update entries (update_head holds the id steps).
std::vector<std::uint32_t> updated_ids(const protocol::pb::Snapshot& s) {
    std::vector<std::uint32_t> out;
    std::uint64_t id = 0;
    for (int i = 0; i < s.update_head_size(); ++i) {
        const std::uint64_t step = s.update_head(i) >> protocol::kHeadFieldBitCount;
        id = i == 0 ? step : id + step;
        out.push_back(static_cast<std::uint32_t>(id));
    }
    return out;
}

TEST(ReplicationState, EnterThenUpdateThenLeave) {
    interest::GameWorld world(world_settings(config_with_bots(3)),
                              testing::rooms_map()); // ids 1, 2, 3
    ReplicationState state;
    protocol::pb::Snapshot snap;

    const auto first = near({1, 3});
    state.build_snapshot(world, first, 1, false, snap);
    ASSERT_EQ(snap.enter_size(), 2);
    EXPECT_EQ(snap.enter(0).id(), 1u);
    EXPECT_EQ(snap.enter(1).id(), 3u);
    EXPECT_EQ(snap.update_head_size(), 0);
    EXPECT_EQ(snap.leave_size(), 0);
    EXPECT_EQ(snap.server_tick(), 1u);

    // Nothing moved: no updates.
    state.build_snapshot(world, first, 2, false, snap);
    EXPECT_EQ(snap.enter_size() + snap.update_head_size() + snap.leave_size(), 0);

    world.step(0.1f); // bots move
    const auto second = near({2, 3});
    state.build_snapshot(world, second, 3, false, snap);
    ASSERT_EQ(snap.enter_size(), 1);
    EXPECT_EQ(snap.enter(0).id(), 2u);
    EXPECT_EQ(updated_ids(snap), std::vector<std::uint32_t>{3});
    EXPECT_EQ(ids(snap.leave()), std::vector<std::uint32_t>{1});
    EXPECT_EQ(state.known(), id_list(second));
}

TEST(ReplicationState, RemovedEntityLeaves) {
    interest::GameWorld world(world_settings(config_with_bots(2)), testing::rooms_map());
    ReplicationState state;
    protocol::pb::Snapshot snap;
    state.build_snapshot(world, near({1, 2}), 1, false, snap);
    world.remove(2);
    state.build_snapshot(world, near({1}), 2, false, snap);
    EXPECT_EQ(ids(snap.leave()), std::vector<std::uint32_t>{2});
    EXPECT_EQ(state.known_count(), 1u);
}

TEST(ReplicationState, CoarseTiersAreUpdatedEverySecondAndFourthTick) {
    interest::GameWorld world(world_settings(config_with_bots(12)), testing::rooms_map());
    ReplicationState state;
    protocol::pb::Snapshot snap;
    std::vector<interest::Interest> set;
    for (std::uint32_t id = 1; id <= 12; ++id) {
        set.push_back({id, static_cast<std::uint8_t>(id % 3)});
    }
    state.build_snapshot(world, set, 1, false, snap);
    std::vector<int> updates(13, 0);
    for (std::uint64_t tick = 2; tick < 2 + 40; ++tick) {
        world.step(1.0f / 30.0f);
        state.build_snapshot(world, set, tick, false, snap);
        for (const auto id : updated_ids(snap)) {
            const std::uint64_t interval = std::uint64_t{1} << (id % 3);
            EXPECT_EQ((tick + id) % interval, 0u) << "entity " << id << " tick " << tick;
            ++updates[id];
        }
    }
    // Every bot walks: near ones are updated (almost) every tick, far ones 1 in 4.
    for (std::uint32_t id = 1; id <= 12; ++id) {
        const int due = 40 >> (id % 3);
        EXPECT_GE(updates[id], due * 3 / 4) << "entity " << id;
        EXPECT_LE(updates[id], due) << "entity " << id;
    }
}

TEST(ReplicationState, RandomSequencesKeepTheDecodedReplicaExact) {
    interest::GameWorld world(world_settings(config_with_bots(40)), testing::rooms_map());
    const protocol::QuantizationSettings quantization;
    ReplicationState state(quantization);
    protocol::SnapshotDecoder client(quantization);
    protocol::pb::Snapshot snap;
    std::mt19937 rng(3);
    std::uint64_t audited = 0;
    for (int tick = 1; tick <= 300; ++tick) {
        world.step(1.0f / 30.0f);
        std::vector<interest::Interest> interest;
        for (std::uint32_t id = 1; id <= 40; ++id) {
            if (rng() % 3 != 0) {
                interest.push_back({id, static_cast<std::uint8_t>(rng() % 3)});
            }
        }
        state.build_snapshot(world, interest, static_cast<std::uint64_t>(tick), true, snap);
        protocol::pb::Snapshot wire; // through the real encoder
        ASSERT_TRUE(wire.ParseFromString(snap.SerializeAsString()));
        const auto problems = client.apply(wire);
        ASSERT_TRUE(problems.empty()) << problems.front().kind << ": " << problems.front().detail;
        double worst = 0.0;
        const auto audit = client.check_audit(wire, worst);
        ASSERT_TRUE(audit.empty()) << audit.front().detail;
        EXPECT_LE(worst, 0.5 + 1e-3);
        audited += static_cast<std::uint64_t>(wire.audit_size());
        ASSERT_EQ(client.size(), interest.size()) << "tick " << tick;
        for (const auto& i : interest) {
            ASSERT_TRUE(client.knows(i.id)) << "tick " << tick << " entity " << i.id;
        }
    }
    EXPECT_GT(audited, 300u * 10u); // most known entities are current on most ticks
}

TEST(ReplicationState, ACrowdEntersOverSeveralSnapshotsSeenAndNearestFirst) {
    // More entities come into view at once than one acknowledged-delta snapshot enters:
    // the seen ones nearest the eye enter first, the rest in the next snapshots, and no
    // snapshot grows past what the datagrams carry.
    constexpr std::size_t kCrowd = protocol::kMaxEntersPerSnapshot + 600;
    interest::GameWorld world(world_settings(config_with_bots(static_cast<int>(kCrowd))),
                              testing::rooms_map());
    std::mt19937 rng(5);
    for (int i = 0; i < 20; ++i) {
        world.step(1.0f / 30.0f); // spread out from the spawn points
    }
    std::vector<interest::Interest> all;
    for (const interest::Entity& e : world.entities()) {
        all.push_back({e.id, rng() % 4 == 0 ? interest::kHeardTier : std::uint8_t{0}});
    }
    ASSERT_EQ(all.size(), kCrowd);
    const glm::vec3 eye = world.entities().front().move.position;
    const auto distance = [&](std::uint32_t id) {
        return glm::length(world.find(id)->move.position - eye);
    };
    const protocol::QuantizationSettings quantization;
    ReplicationState state(quantization, true);
    protocol::AckedSnapshotDecoder client(quantization);
    protocol::pb::Snapshot snap;

    state.build_acked_snapshot(world, all, eye, 1, std::nullopt, false, snap);
    EXPECT_EQ(state.last_acked().enters, protocol::kMaxEntersPerSnapshot);
    EXPECT_EQ(state.last_deferred(), kCrowd - protocol::kMaxEntersPerSnapshot);
    EXPECT_LE(snap.ByteSizeLong(), protocol::kMaxSnapshotBytes);
    // Every seen entity that entered is nearer than every seen one left out, and a heard
    // one entered only if every seen one did.
    std::vector<std::uint32_t> known = state.known();
    float farthest_in = 0.0f;
    float nearest_out = 1e30f;
    std::size_t heard_in = 0;
    std::size_t seen_out = 0;
    for (const interest::Interest& i : all) {
        const bool in = std::binary_search(known.begin(), known.end(), i.id);
        if (i.tier == interest::kHeardTier) {
            heard_in += in ? 1 : 0;
        } else if (in) {
            farthest_in = std::max(farthest_in, distance(i.id));
        } else {
            nearest_out = std::min(nearest_out, distance(i.id));
            ++seen_out;
        }
    }
    EXPECT_GT(seen_out, 0u); // the test's crowd has more seen entities than one snapshot takes
    EXPECT_EQ(heard_in, 0u);
    EXPECT_LE(farthest_in, nearest_out);
    protocol::pb::Snapshot wire;
    ASSERT_TRUE(wire.ParseFromString(snap.SerializeAsString()));
    auto problems = client.apply(wire);
    ASSERT_TRUE(problems.empty()) << problems.front().kind << ": " << problems.front().detail;
    ASSERT_NE(client.newest(), nullptr);
    EXPECT_EQ(client.newest()->entities.size(), protocol::kMaxEntersPerSnapshot);

    // Acknowledged: the rest enter, and the client knows the whole crowd.
    world.step(1.0f / 30.0f);
    state.build_acked_snapshot(world, all, eye, 2, 1, false, snap);
    EXPECT_EQ(state.last_acked().enters, kCrowd - protocol::kMaxEntersPerSnapshot);
    EXPECT_EQ(state.last_deferred(), 0u);
    ASSERT_TRUE(wire.ParseFromString(snap.SerializeAsString()));
    problems = client.apply(wire);
    ASSERT_TRUE(problems.empty()) << problems.front().kind << ": " << problems.front().detail;
    EXPECT_EQ(client.newest()->entities.size(), kCrowd);

    // Fewer than the limit wanted: nothing is deferred (the usual case, no choice made).
    ReplicationState small(quantization, true);
    const std::vector<interest::Interest> some(all.begin(), all.begin() + 100);
    small.build_acked_snapshot(world, some, eye, 1, std::nullopt, false, snap);
    EXPECT_EQ(small.last_acked().enters, 100u);
    EXPECT_EQ(small.last_deferred(), 0u);
}

} // namespace
} // namespace dsoc::server
