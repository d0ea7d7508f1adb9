// buffer_room.hpp: a connection's per-tick buffers keep room for twice their last use,
// and give back what a past peak left beyond that.
#include "dsoc/protocol/buffer_room.hpp"
#include "dsoc/protocol/update_columns.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

namespace dsoc::protocol {
namespace {

TEST(BufferRoom, RoomBeyondTwiceTheLastUseAndTheSlackIsOversized) {
    EXPECT_FALSE(room_oversized(2 * 100 + 64, 100, 64));
    EXPECT_TRUE(room_oversized(2 * 100 + 65, 100, 64));
    EXPECT_FALSE(room_oversized(64, 0, 64));
    EXPECT_TRUE(room_oversized(65, 0, 64));
}

TEST(BufferRoom, AVectorKeepsItsRoomNearItsUseAndGivesBackAPeak) {
    std::vector<std::uint8_t> buffer(10000, 1); // a peak
    clear_to_need(buffer, 64);
    EXPECT_TRUE(buffer.empty());
    EXPECT_GE(buffer.capacity(), 10000u) << "the use it just had: kept";
    buffer.resize(6000, 1);
    clear_to_need(buffer, 64);
    EXPECT_GE(buffer.capacity(), 10000u) << "within twice the use: kept, no reallocation";
    buffer.resize(100, 1);
    clear_to_need(buffer, 64);
    EXPECT_TRUE(buffer.empty());
    EXPECT_EQ(buffer.capacity(), 0u) << "the peak is given back";
}

void fill(pb::Snapshot& snapshot, int entries) {
    snapshot.set_server_tick(7);
    for (int i = 0; i < entries; ++i) {
        snapshot.add_enter()->set_id(static_cast<std::uint32_t>(i));
        snapshot.add_update_head(static_cast<std::uint64_t>(i));
    }
}

TEST(BufferRoom, ASnapshotMessageGivesBackItsEntitiesAfterAPeak) {
    pb::Snapshot snapshot;
    fill(snapshot, 500);
    clear_to_need(snapshot);
    EXPECT_EQ(snapshot.enter_size(), 0);
    EXPECT_EQ(snapshot.server_tick(), 0u);
    EXPECT_GE(snapshot.enter().Capacity(), 500) << "kept for a snapshot like the last";
    EXPECT_GE(snapshot.enter().ClearedCount(), 500) << "its entity messages kept for reuse";
    fill(snapshot, 400);
    clear_to_need(snapshot);
    EXPECT_GE(snapshot.enter().ClearedCount(), 500) << "within twice the use: kept";
    fill(snapshot, 3);
    EXPECT_EQ(snapshot.enter_size(), 3);
    clear_to_need(snapshot);
    EXPECT_EQ(snapshot.enter_size(), 0);
    EXPECT_EQ(snapshot.enter().Capacity(), 0) << "the peak's entity messages are freed";
    EXPECT_EQ(snapshot.update_head().Capacity(), 0);
    EXPECT_EQ(snapshot.ByteSizeLong(), 0u);
}

TEST(BufferRoom, UpdateColumnsGiveBackAPeak) {
    const std::array<std::int32_t, 3> values{1, -2, 3};
    UpdateColumns columns;
    const auto add = [&](int entries) {
        for (int i = 0; i < entries; ++i) {
            columns.add(1, 7, values);
        }
    };
    add(1000);
    columns.clear();
    EXPECT_GE(columns.capacity(), 1000u);
    add(600);
    columns.clear();
    EXPECT_GE(columns.capacity(), 1000u) << "within twice the use: kept";
    add(10);
    const std::size_t bytes_after_peak = columns.wire_bytes();
    columns.clear();
    EXPECT_EQ(columns.capacity(), 0u) << "the peak is given back";
    add(10);
    EXPECT_EQ(columns.count(), 10u);
    EXPECT_EQ(columns.wire_bytes(), bytes_after_peak) << "and the columns grow again";
}

} // namespace
} // namespace dsoc::protocol
