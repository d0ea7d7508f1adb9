// The update columns written in wire form (UpdateColumns, encode_snapshot_frame,
// append_snapshot_envelope) against their obviously correct twin: the same entries as
// protobuf repeated fields, serialized by protobuf. Random connections, tick after tick,
// for the compact and the acknowledged-delta encoders: the bytes must be the same.

#include "dsoc/protocol/acked_snapshot.hpp"
#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/update_columns.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <vector>

namespace dsoc::protocol {
namespace {

const std::array<float, 3> kHalf{15.0f, 15.0f, 28.0f};

void add_audit(std::uint32_t id, const Pose& p, pb::Snapshot& s) {
    pb::AuditPose& a = *s.add_audit();
    a.set_id(id);
    a.set_x(p.x);
    a.set_y(p.y);
    a.set_z(p.z);
    a.set_yaw(p.yaw_deg);
    a.set_pitch(p.pitch_deg);
}

TEST(UpdateColumns, FramesAreByteForByteThoseOfTheRepeatedFields) {
    std::mt19937 rng(20261127);
    std::uniform_real_distribution<float> step(-40.0f, 40.0f);
    std::uniform_real_distribution<float> turn(-30.0f, 30.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_int_distribution<int> tier_of(0, static_cast<int>(kTiers) - 1);
    std::size_t updates = 0;
    std::size_t audited = 0;
    std::size_t empty_columns = 0;
    for (int connection = 0; connection < 12; ++connection) {
        const QuantizationSettings settings;
        SnapshotEncoder twin(settings); // into the repeated fields
        SnapshotEncoder fast(settings); // into the columns
        UpdateColumns columns;
        pb::Envelope twin_envelope;
        pb::Envelope fast_envelope;
        std::map<std::uint32_t, Pose> world; // id -> pose; ids up to large values
        std::map<std::uint32_t, std::uint8_t> known;
        const float moving = unit(rng); // how many entities move each tick
        for (std::uint64_t tick = 1; tick <= 150; ++tick) {
            twin.begin(tick, *twin_envelope.mutable_snapshot());
            fast.begin(tick, *fast_envelope.mutable_snapshot(), &columns);
            pb::Snapshot& a = *twin_envelope.mutable_snapshot();
            pb::Snapshot& b = *fast_envelope.mutable_snapshot();
            // Entities join the world now and then, some with ids past 2^31.
            while (world.size() < 40 || unit(rng) < 0.2f) {
                const std::uint32_t id =
                    unit(rng) < 0.1f ? 0x80000000u + rng() % 1000u : 1u + rng() % 5000u;
                world[id] = {step(rng) * 50.0f, step(rng) * 50.0f, step(rng) * 5.0f,
                             turn(rng) * 6.0f, turn(rng) * 3.0f};
            }
            const bool audit = unit(rng) < 0.15f;
            for (auto& [id, pose] : world) {
                if (unit(rng) < moving) {
                    pose.x += step(rng);
                    pose.y += step(rng);
                    pose.z += unit(rng) < 0.2f ? step(rng) : 0.0f;
                    pose.yaw_deg = std::fmod(pose.yaw_deg + turn(rng) + 540.0f, 360.0f) - 180.0f;
                    pose.pitch_deg = std::clamp(pose.pitch_deg + turn(rng) * 0.1f, -89.0f, 89.0f);
                }
                const auto it = known.find(id);
                const bool wanted = unit(rng) < 0.85f;
                if (it == known.end()) {
                    if (wanted) {
                        const auto tier = static_cast<std::uint8_t>(tier_of(rng));
                        twin.enter(id, pose, kHalf, 1, tier, a);
                        fast.enter(id, pose, kHalf, 1, tier, b);
                        known[id] = tier;
                    }
                } else if (!wanted) {
                    twin.leave(id, a);
                    fast.leave(id, b);
                    known.erase(it);
                    continue;
                } else {
                    if (unit(rng) < 0.05f) {
                        it->second = static_cast<std::uint8_t>(tier_of(rng)); // a rebase
                    }
                    const std::uint32_t written = twin.update(id, pose, it->second, a);
                    ASSERT_EQ(fast.update(id, pose, it->second, b), written) << id;
                    updates += written != 0 ? 1 : 0;
                }
                if (audit) {
                    add_audit(id, pose, a);
                    add_audit(id, pose, b);
                }
            }
            ASSERT_EQ(b.update_head_size(), 0);
            ASSERT_EQ(columns.count(), static_cast<std::size_t>(a.update_head_size()));
            ASSERT_EQ(columns.wire_bytes(), update_column_bytes(a));
            empty_columns += columns.count() == 0 ? 1 : 0;
            audited += static_cast<std::size_t>(b.audit_size());
            const std::string before = fast_envelope.SerializeAsString();
            std::vector<std::uint8_t> twin_frame{0xab}; // both append after what is there
            std::vector<std::uint8_t> fast_frame{0xab};
            const std::size_t twin_bytes = encode_frame(twin_envelope, twin_frame);
            ASSERT_EQ(encode_snapshot_frame(fast_envelope, columns, fast_frame), twin_bytes);
            ASSERT_EQ(fast_frame, twin_frame) << "connection " << connection << " tick " << tick;
            ASSERT_EQ(fast_envelope.SerializeAsString(), before) << "the envelope was changed";
        }
    }
    // The random connections covered what they mean to: updates, audits, and ticks
    // where nothing moved.
    EXPECT_GT(updates, 10000u);
    EXPECT_GT(audited, 1000u);
    EXPECT_GT(empty_columns, 0u);
}

TEST(UpdateColumns, AckedSnapshotsAreByteForByteThoseOfTheRepeatedFields) {
    std::mt19937 rng(20261128);
    std::uniform_real_distribution<float> step(-40.0f, 40.0f);
    std::uniform_real_distribution<float> turn(-30.0f, 30.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_int_distribution<int> tier_of(0, static_cast<int>(kTiers) - 1);
    std::size_t entries = 0;
    std::size_t against_baseline = 0;
    std::size_t whole = 0;
    std::size_t audited = 0;
    for (int connection = 0; connection < 12; ++connection) {
        const QuantizationSettings settings;
        AckedSnapshotEncoder twin(settings); // into the repeated fields
        AckedSnapshotEncoder fast(settings); // into the columns
        UpdateColumns columns;
        pb::Envelope twin_envelope;
        pb::Envelope fast_envelope;
        std::map<std::uint32_t, std::pair<Pose, std::uint8_t>> world; // id -> pose, tier
        std::optional<std::uint64_t> acked;
        const float moving = unit(rng);
        for (std::uint64_t tick = 1; tick <= 150; ++tick) {
            // The client acknowledges a recent tick most of the time, now and then none
            // for a while (whole snapshots once the baseline is too old).
            if (unit(rng) < 0.7f && tick > 1) {
                const std::uint64_t back = 1 + rng() % 4;
                acked = std::max(acked.value_or(0), tick > back ? tick - back : 1);
            }
            twin.begin(tick, acked, *twin_envelope.mutable_snapshot());
            fast.begin(tick, acked, *fast_envelope.mutable_snapshot(), &columns);
            pb::Snapshot& a = *twin_envelope.mutable_snapshot();
            pb::Snapshot& b = *fast_envelope.mutable_snapshot();
            while (world.size() < 40 || unit(rng) < 0.2f) {
                const std::uint32_t id =
                    unit(rng) < 0.1f ? 0x80000000u + rng() % 1000u : 1u + rng() % 5000u;
                world[id] = {{step(rng) * 50.0f, step(rng) * 50.0f, step(rng) * 5.0f,
                              turn(rng) * 6.0f, turn(rng) * 3.0f},
                             static_cast<std::uint8_t>(tier_of(rng))};
            }
            const bool audit = unit(rng) < 0.15f;
            for (auto& [id, entity] : world) {
                auto& [pose, tier] = entity;
                if (unit(rng) < moving) {
                    pose.x += step(rng) * 0.2f;
                    pose.y += step(rng) * 0.2f;
                    pose.z += unit(rng) < 0.2f ? step(rng) : 0.0f;
                    pose.yaw_deg = std::fmod(pose.yaw_deg + turn(rng) + 540.0f, 360.0f) - 180.0f;
                }
                if (unit(rng) < 0.02f) {
                    tier = static_cast<std::uint8_t>(tier_of(rng)); // a rebase
                }
                if (unit(rng) < 0.1f) {
                    continue; // not wanted this tick: leaves, or stays unknown
                }
                const QuantizedPose q = quantize(pose, settings, tier);
                twin.add(id, q, tier, 1, kHalf, a);
                fast.add(id, q, tier, 1, kHalf, b);
                if (audit) {
                    add_audit(id, pose, a);
                    add_audit(id, pose, b);
                }
            }
            const AckedSnapshotCounts twin_counts = twin.finish(a);
            const AckedSnapshotCounts fast_counts = fast.finish(b);
            ASSERT_EQ(fast_counts.entries, twin_counts.entries);
            ASSERT_EQ(b.update_head_size(), 0);
            ASSERT_EQ(columns.count(), static_cast<std::size_t>(a.update_head_size()));
            entries += twin_counts.entries;
            against_baseline += twin_counts.coded_against_baseline ? 1 : 0;
            whole += twin_counts.coded_against_baseline ? 0 : 1;
            audited += static_cast<std::size_t>(b.audit_size());
            const std::string before = fast_envelope.SerializeAsString();
            std::vector<std::uint8_t> fast_bytes{0xab}; // appended after what is there
            const std::string twin_bytes = twin_envelope.SerializeAsString();
            ASSERT_EQ(append_snapshot_envelope(fast_envelope, columns, fast_bytes),
                      twin_bytes.size());
            ASSERT_EQ(std::string(fast_bytes.begin() + 1, fast_bytes.end()), twin_bytes)
                << "connection " << connection << " tick " << tick;
            ASSERT_EQ(fast_envelope.SerializeAsString(), before) << "the envelope was changed";
        }
    }
    EXPECT_GT(entries, 10000u);
    EXPECT_GT(against_baseline, 1000u);
    EXPECT_GT(whole, 12u);
    EXPECT_GT(audited, 1000u);
}

TEST(UpdateColumns, ClearKeepsNothingOfTheLastSnapshot) {
    UpdateColumns columns;
    const std::array<std::int32_t, 2> values{-3, 70000};
    columns.add(7, kFieldX | kFieldZ, values);
    EXPECT_EQ(columns.count(), 1u);
    // Tags and lengths (1 + 1 each), then the head 7 << 4 | 5 = 117 (1 byte; the mask
    // needs nothing apart), -3 -> 5 (1) and 70000 -> 140000 (3 bytes).
    EXPECT_EQ(columns.wire_bytes(), 2u + 1u + 2u + 4u);
    columns.clear();
    EXPECT_EQ(columns.count(), 0u);
    EXPECT_EQ(columns.wire_bytes(), 0u);
    std::array<std::uint8_t, 4> out{};
    EXPECT_EQ(columns.write(out.data()), out.data()); // nothing written
}

} // namespace
} // namespace dsoc::protocol
