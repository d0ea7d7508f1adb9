#include "dsoc/protocol/acked_snapshot.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/datagram.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/replication_state.hpp"
#include "dsoc/server/udp_connection.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

/// A client over UDP, as the server and its clients run one: snapshots built with update
/// columns (unless `with_columns` is false: in the snapshot's repeated fields), framed as
/// the server frames them, parsed and applied by the real decoder, each acknowledged before
/// the next tick.
struct UdpClient {
    explicit UdpClient(const protocol::QuantizationSettings& q, bool with_columns = true)
        : state(q, true), decoder(q), columns(with_columns ? &column_memory : nullptr) {}

    /// Builds, sends and applies the snapshot of `tick`; the snapshot as the client got it.
    protocol::pb::Snapshot send(const interest::GameWorld& world,
                                const std::vector<interest::Interest>& interest, glm::vec3 eye,
                                std::uint64_t tick, bool audit = false) {
        state.build_acked_snapshot(world, interest, eye, tick, decoder.newest_tick(), audit,
                                   *envelope.mutable_snapshot(), nullptr, columns);
        snapshot_frame(tick, envelope, columns, frame);
        const std::size_t bytes = frame.size() - 8; // after the tick: the datagrams' payload
        EXPECT_LE(bytes, protocol::kMaxSnapshotBytes) << "tick " << tick;
        largest = std::max(largest, bytes);
        protocol::pb::Envelope wire;
        EXPECT_TRUE(wire.ParseFromArray(frame.data() + 8, static_cast<int>(bytes)));
        const auto problems = decoder.apply(wire.snapshot());
        EXPECT_TRUE(problems.empty())
            << "tick " << tick << ": " << problems.front().kind << ": " << problems.front().detail;
        return wire.snapshot();
    }

    ReplicationState state;
    protocol::AckedSnapshotDecoder decoder;
    protocol::pb::Envelope envelope;
    protocol::UpdateColumns column_memory;
    protocol::UpdateColumns* columns;
    std::vector<std::uint8_t> frame;
    std::size_t largest = 0; ///< the largest envelope sent [bytes]
};

/// `count` bots with ids first, first + 1, ... at random places within `spread` world
/// units of the origin, facing anywhere.
std::vector<interest::Entity> scattered(std::uint32_t first, std::uint32_t count, float spread,
                                        std::mt19937& rng) {
    std::uniform_real_distribution<float> coordinate(-spread, spread);
    std::uniform_real_distribution<float> yaw(-180.0f, 180.0f);
    std::vector<interest::Entity> out(count);
    for (std::uint32_t k = 0; k < count; ++k) {
        out[k].id = first + k;
        out[k].kind = interest::EntityKind::bot;
        out[k].move.position = {coordinate(rng), coordinate(rng), coordinate(rng)};
        out[k].yaw_deg = yaw(rng);
    }
    return out;
}

// A client knows 8,000 entities that all jump about their places every tick, never where
// their motion predicts: their update entries alone (about 12 bytes each) are over the
// 75,008 bytes a snapshot's datagrams carry. It still gets a snapshot every tick, within
// the limit; the entries left out are the farthest, yet none waits long (the far ones
// stay far); once the crowd stands, its replica is the world.
void updates_beyond_the_datagrams(bool with_columns) {
    constexpr std::uint32_t kCount = 8000;
    interest::GameWorld world(world_settings(config_with_bots(0)), testing::rooms_map());
    std::mt19937 rng(7);
    std::vector<interest::Entity> crowd = scattered(1, kCount, 8000.0f, rng);
    world.mirror(crowd, 0, kCount + 1);
    std::vector<interest::Interest> all;
    for (const interest::Entity& e : crowd) {
        all.push_back({e.id, 0});
    }
    const glm::vec3 eye(0.0f);
    const protocol::QuantizationSettings quantization;
    UdpClient client(quantization, with_columns);
    std::uint64_t tick = 0;
    // The crowd enters over a few snapshots (at most 1,024 a snapshot), standing.
    while (client.decoder.newest() == nullptr ||
           client.decoder.newest()->entities.size() < kCount) {
        ASSERT_LT(tick, 12u);
        client.send(world, all, eye, ++tick);
        EXPECT_EQ(client.state.last_updates_deferred(), 0u);
    }

    // It moves: every entity needs an entry every tick.
    std::vector<std::uint64_t> last_written(kCount + 1, tick);
    std::uint64_t longest_wait = 0;
    std::size_t deferred = 0;
    std::size_t audited = 0;
    const std::vector<interest::Entity> places = crowd;
    std::uniform_real_distribution<float> jump(-2000.0f, 2000.0f);
    std::uniform_real_distribution<float> facing(-180.0f, 180.0f);
    for (int moving = 0; moving < 16; ++moving) {
        for (std::size_t k = 0; k < crowd.size(); ++k) {
            crowd[k].move.position =
                places[k].move.position + glm::vec3(jump(rng), jump(rng), jump(rng));
            crowd[k].yaw_deg = facing(rng);
        }
        world.mirror(crowd, 0, kCount + 1);
        const bool audit = moving % 5 == 4;
        const protocol::pb::Snapshot got = client.send(world, all, eye, ++tick, audit);
        ASSERT_EQ(got.server_tick(), tick);
        ASSERT_TRUE(got.has_baseline_tick());
        const std::vector<std::uint32_t> written = updated_ids(got);
        EXPECT_EQ(written.size() + client.state.last_updates_deferred(), kCount);
        EXPECT_GT(client.state.last_updates_deferred(), 0u) << "tick " << tick;
        EXPECT_EQ(client.state.known_count(), kCount); // deferred entries stay known
        deferred += client.state.last_updates_deferred();
        if (moving == 0) {
            // Nothing waited before: the written entries are the nearest.
            std::vector<std::uint8_t> in(kCount + 1, 0);
            for (const auto id : written) {
                in[id] = 1;
            }
            float farthest_in = 0.0f;
            float nearest_out = 1e30f;
            for (const interest::Entity& e : crowd) {
                const float d = glm::length(e.move.position - eye);
                if (in[e.id] != 0) {
                    farthest_in = std::max(farthest_in, d);
                } else {
                    nearest_out = std::min(nearest_out, d);
                }
            }
            EXPECT_LE(farthest_in, nearest_out);
        }
        if (audit) {
            // Audit poses only of what the snapshot made current, each within the quantum.
            double worst = 0.0;
            const auto problems = client.decoder.check_audit(got, worst);
            EXPECT_TRUE(problems.empty()) << problems.front().detail;
            EXPECT_LE(worst, 0.5 + 1e-3);
            audited += static_cast<std::size_t>(got.audit_size());
        }
        for (const auto id : written) {
            longest_wait = std::max(longest_wait, tick - last_written[id]);
            last_written[id] = tick;
        }
    }
    for (std::uint32_t id = 1; id <= kCount; ++id) {
        longest_wait = std::max(longest_wait, tick - last_written[id]);
    }
    // Under a load that never fits, an entity left out ReplicationState::kPromoteAfter (3)
    // times goes first: none waits much longer (here 4 ticks; by distance alone, the
    // farthest would wait for good).
    static_assert(ReplicationState::kPromoteAfter <= 3);
    EXPECT_LE(longest_wait, 6u);
    EXPECT_GT(deferred, 16u * 1000u);
    EXPECT_GT(client.largest, protocol::kMaxSnapshotBytes * 9 / 10); // the room is used
    EXPECT_GT(audited, 0u);

    // The crowd stands: within a few snapshots every entity is where the world has it.
    for (int standing = 0; standing < 8; ++standing) {
        client.send(world, all, eye, ++tick);
    }
    EXPECT_EQ(client.state.last_updates_deferred(), 0u);
    ASSERT_EQ(client.decoder.newest()->entities.size(), kCount);
    const float half = 0.5f * quantization.quantum(0) + 1e-3f;
    const float half_step = 180.0f / static_cast<float>(quantization.angle_steps) + 1e-3f;
    for (const interest::Entity& e : crowd) {
        const auto pose = client.decoder.pose(e.id);
        ASSERT_TRUE(pose.has_value()) << "entity " << e.id;
        ASSERT_NEAR(pose->x, e.move.position.x, half) << "entity " << e.id;
        ASSERT_NEAR(pose->y, e.move.position.y, half) << "entity " << e.id;
        ASSERT_NEAR(pose->z, e.move.position.z, half) << "entity " << e.id;
        const float yaw = std::remainder(pose->yaw_deg - e.yaw_deg, 360.0f);
        ASSERT_LE(std::abs(yaw), half_step) << "entity " << e.id;
    }
}

TEST(ReplicationState, UpdatesBeyondTheDatagramsAreDeferredNearestFirstThenRepaired) {
    for (const bool with_columns : {true, false}) {
        SCOPED_TRACE(with_columns ? "update columns" : "repeated fields");
        updates_beyond_the_datagrams(with_columns);
    }
}

TEST(ReplicationState, LeavesBeyondTheDatagramsCodeTheSnapshotAgainstNothing) {
    // A client that knows 20,000 entities with 4-byte ids turns away from all of them at
    // once: their leaves alone are over what a snapshot's datagrams carry. The snapshot is
    // coded against nothing instead (it leaves nothing: the client forgets what it does
    // not hold), and the client knows exactly its new set.
    constexpr std::uint32_t kFar = 20000;
    constexpr std::uint32_t kFirstFar = std::uint32_t{1} << 21; // a 4-byte varint
    interest::GameWorld world(world_settings(config_with_bots(0)), testing::rooms_map());
    std::mt19937 rng(9);
    std::vector<interest::Entity> entities = scattered(1, 50, 500.0f, rng);
    for (const interest::Entity& e : scattered(kFirstFar, kFar, 4000.0f, rng)) {
        entities.push_back(e);
    }
    world.mirror(entities, 0, kFirstFar + kFar);
    std::vector<interest::Interest> all;
    std::vector<interest::Interest> near_ones;
    for (const interest::Entity& e : entities) {
        all.push_back({e.id, 0});
        if (e.id < kFirstFar) {
            near_ones.push_back({e.id, 0});
        }
    }
    const protocol::QuantizationSettings quantization;
    UdpClient client(quantization);
    std::uint64_t tick = 0;
    while (client.decoder.newest() == nullptr ||
           client.decoder.newest()->entities.size() < all.size()) {
        ASSERT_LT(tick, 30u);
        client.send(world, all, glm::vec3(0.0f), ++tick);
    }
    const protocol::pb::Snapshot got = client.send(world, near_ones, glm::vec3(0.0f), ++tick);
    EXPECT_FALSE(got.has_baseline_tick());
    EXPECT_EQ(got.leave_size(), 0);
    EXPECT_EQ(got.enter_size(), static_cast<int>(near_ones.size()));
    EXPECT_EQ(client.state.known(), id_list(near_ones));
    ASSERT_EQ(client.decoder.newest()->entities.size(), near_ones.size());
    // Back to deltas once that frame is acknowledged.
    const protocol::pb::Snapshot next = client.send(world, near_ones, glm::vec3(0.0f), ++tick);
    EXPECT_TRUE(next.has_baseline_tick());
    EXPECT_EQ(next.enter_size() + next.leave_size(), 0);
}

} // namespace
} // namespace dsoc::server
