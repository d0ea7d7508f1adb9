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

/// The random draws of the twin tests: steps and turns of moving entities, shares, tiers.
/// (The draws of a new entity are in the order the first test made them: its figures stay.)
struct Dice {
    explicit Dice(std::uint32_t seed) : rng(seed) {}
    float step() { return step_(rng); }
    float turn() { return turn_(rng); }
    float unit() { return unit_(rng); }
    int tier() { return tier_(rng); }
    /// An entity joining the world: its id (some past 2^31) and where it is.
    std::uint32_t new_id() {
        return unit() < 0.1f ? 0x80000000u + rng() % 1000u : 1u + rng() % 5000u;
    }
    Pose new_pose() {
        return {step() * 50.0f, step() * 50.0f, step() * 5.0f, turn() * 6.0f, turn() * 3.0f};
    }

    std::mt19937 rng;

private:
    std::uniform_real_distribution<float> step_{-40.0f, 40.0f};
    std::uniform_real_distribution<float> turn_{-30.0f, 30.0f};
    std::uniform_real_distribution<float> unit_{0.0f, 1.0f};
    std::uniform_int_distribution<int> tier_{0, static_cast<int>(kTiers) - 1};
};

/// One encoder writing into the snapshot's repeated fields (the twin), one into columns.
template <typename Encoder>
struct Twins {
    explicit Twins(const QuantizationSettings& settings) : twin(settings), fast(settings) {}
    Encoder twin;
    Encoder fast;
    UpdateColumns columns;
    pb::Envelope twin_envelope;
    pb::Envelope fast_envelope;
};

TEST(UpdateColumns, FramesAreByteForByteThoseOfTheRepeatedFields) {
    Dice dice(20261127);
    std::size_t updates = 0;
    std::size_t audited = 0;
    std::size_t empty_columns = 0;
    for (int connection = 0; connection < 12; ++connection) {
        Twins<SnapshotEncoder> t{QuantizationSettings{}};
        auto& [twin, fast, columns, twin_envelope, fast_envelope] = t;
        std::map<std::uint32_t, Pose> world; // id -> pose; ids up to large values
        std::map<std::uint32_t, std::uint8_t> known;
        const float moving = dice.unit(); // how many entities move each tick
        for (std::uint64_t tick = 1; tick <= 150; ++tick) {
            twin.begin(tick, *twin_envelope.mutable_snapshot());
            fast.begin(tick, *fast_envelope.mutable_snapshot(), &columns);
            pb::Snapshot& a = *twin_envelope.mutable_snapshot();
            pb::Snapshot& b = *fast_envelope.mutable_snapshot();
            // Entities join the world now and then, some with ids past 2^31.
            while (world.size() < 40 || dice.unit() < 0.2f) {
                const std::uint32_t id = dice.new_id();
                world[id] = dice.new_pose();
            }
            const bool audit = dice.unit() < 0.15f;
            for (auto& [id, pose] : world) {
                if (dice.unit() < moving) {
                    pose.x += dice.step();
                    pose.y += dice.step();
                    pose.z += dice.unit() < 0.2f ? dice.step() : 0.0f;
                    pose.yaw_deg = std::fmod(pose.yaw_deg + dice.turn() + 540.0f, 360.0f) - 180.0f;
                    pose.pitch_deg = std::clamp(pose.pitch_deg + dice.turn() * 0.1f, -89.0f, 89.0f);
                }
                const auto it = known.find(id);
                const bool wanted = dice.unit() < 0.85f;
                if (it == known.end()) {
                    if (wanted) {
                        const auto tier = static_cast<std::uint8_t>(dice.tier());
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
                    if (dice.unit() < 0.05f) {
                        it->second = static_cast<std::uint8_t>(dice.tier()); // a rebase
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
    Dice dice(20261128);
    std::size_t entries = 0;
    std::size_t against_baseline = 0;
    std::size_t whole = 0;
    std::size_t audited = 0;
    for (int connection = 0; connection < 12; ++connection) {
        const QuantizationSettings settings;
        Twins<AckedSnapshotEncoder> t{settings};
        auto& [twin, fast, columns, twin_envelope, fast_envelope] = t;
        std::map<std::uint32_t, std::pair<Pose, std::uint8_t>> world; // id -> pose, tier
        std::optional<std::uint64_t> acked;
        const float moving = dice.unit();
        for (std::uint64_t tick = 1; tick <= 150; ++tick) {
            // The client acknowledges a recent tick most of the time, now and then none
            // for a while (whole snapshots once the baseline is too old).
            if (dice.unit() < 0.7f && tick > 1) {
                const std::uint64_t back = 1 + dice.rng() % 4;
                acked = std::max(acked.value_or(0), tick > back ? tick - back : 1);
            }
            twin.begin(tick, acked, *twin_envelope.mutable_snapshot());
            fast.begin(tick, acked, *fast_envelope.mutable_snapshot(), &columns);
            pb::Snapshot& a = *twin_envelope.mutable_snapshot();
            pb::Snapshot& b = *fast_envelope.mutable_snapshot();
            while (world.size() < 40 || dice.unit() < 0.2f) {
                const std::uint32_t id = dice.new_id();
                const Pose pose = dice.new_pose();
                world[id] = {pose, static_cast<std::uint8_t>(dice.tier())};
            }
            const bool audit = dice.unit() < 0.15f;
            for (auto& [id, entity] : world) {
                auto& [pose, tier] = entity;
                if (dice.unit() < moving) {
                    pose.x += dice.step() * 0.2f;
                    pose.y += dice.step() * 0.2f;
                    pose.z += dice.unit() < 0.2f ? dice.step() : 0.0f;
                    pose.yaw_deg = std::fmod(pose.yaw_deg + dice.turn() + 540.0f, 360.0f) - 180.0f;
                }
                if (dice.unit() < 0.02f) {
                    tier = static_cast<std::uint8_t>(dice.tier()); // a rebase
                }
                if (dice.unit() < 0.1f) {
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
    // append_snapshot_envelope() writes the fields after the columns by hand: the audit
    // poses and the baseline tick are all there are.
    int highest = 0;
    for (int f = 0; f < pb::Snapshot::descriptor()->field_count(); ++f) {
        highest = std::max(highest, pb::Snapshot::descriptor()->field(f)->number());
    }
    EXPECT_EQ(highest, pb::Snapshot::kBaselineTickFieldNumber);
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
