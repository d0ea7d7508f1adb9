// The bench's acknowledged-delta link (AckedClientReplication, what dsoc-snapshot-bytes
// measures): over a lossless link every snapshot after the first is coded against an
// acknowledged frame; over a lossy, slow one the client still holds exactly the
// server's frame after every snapshot it applies, and full snapshots go out only until
// the first acknowledgement arrives.

#include "dsoc/eval/acked_replication.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace dsoc::eval {
namespace {

/// 30 entities running in circles of different sizes, ids 0-29.
WorldFrame circles(std::uint64_t tick) {
    WorldFrame frame;
    frame.tick = tick;
    for (int id = 0; id < 30; ++id) {
        const float angle =
            0.05f * static_cast<float>(tick) * (1.0f + 0.1f * static_cast<float>(id));
        const float radius = 100.0f + 20.0f * static_cast<float>(id);
        EntityFrame e;
        e.position = {radius * std::cos(angle), radius * std::sin(angle), 24.0f};
        e.box = {e.position - glm::vec3(15.0f, 15.0f, 24.0f),
                 e.position + glm::vec3(15.0f, 15.0f, 32.0f)};
        e.yaw_deg = std::fmod(angle * 57.29578f + 90.0f, 360.0f) - 180.0f;
        frame.entities.push_back(e);
    }
    return frame;
}

struct Totals {
    std::uint64_t updates = 0;
    std::uint64_t enters = 0;
};

Totals run(AckedClientReplication& client, int ticks, std::uint32_t seed) {
    std::mt19937 rng(seed);
    protocol::pb::Envelope scratch;
    std::vector<std::uint8_t> buffer;
    Totals totals;
    for (int t = 1; t <= ticks; ++t) {
        const WorldFrame frame = circles(static_cast<std::uint64_t>(t));
        std::vector<std::uint32_t> interest;
        std::vector<std::uint32_t> heard;
        for (std::uint32_t id = 0; id < 30; ++id) {
            if ((id + static_cast<std::uint32_t>(t) / 40) % 3 != 0) { // sets change every 40 ticks
                interest.push_back(id);
                if (rng() % 5 == 0) {
                    heard.push_back(id);
                }
            }
        }
        const SnapshotCost cost =
            client.send(frame, interest, heard, static_cast<std::uint64_t>(t), scratch, buffer);
        totals.updates += cost.updates;
        totals.enters += cost.enters;
    }
    return totals;
}

TEST(AckedReplication, OverALosslessLinkOnlyTheFirstSnapshotIsFull) {
    AckedClientReplication client(10, LinkModel{0, 0.0, 1}, 0);
    const Totals totals = run(client, 300, 1);
    EXPECT_EQ(client.full_snapshots(), 1u);
    EXPECT_EQ(client.mismatches(), 0u);
    EXPECT_TRUE(client.first_problem().empty()) << client.first_problem();
    EXPECT_GT(totals.updates, 0u); // the circles turn: residuals travel
}

TEST(AckedReplication, OverALossySlowLinkTheClientHoldsTheServersFrames) {
    AckedClientReplication client(10, LinkModel{2, 0.2, 7}, 3);
    const Totals totals = run(client, 600, 7);
    EXPECT_EQ(client.mismatches(), 0u);
    EXPECT_GE(client.full_snapshots(), 5u);  // until the first acknowledgement arrives
    EXPECT_LT(client.full_snapshots(), 60u); // then, against acknowledged frames
    EXPECT_GT(totals.enters, 30u);           // the sets changed (and lost enters came again)
}

} // namespace
} // namespace dsoc::eval
