#include "dsoc/protocol/compact_snapshot.hpp"

#include "snapshot_wire.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>

namespace dsoc::protocol {
namespace {

const std::array<float, 3> kHalf{15.0f, 15.0f, 28.0f};

TEST(Quantization, RoundTripIsWithinHalfAQuantum) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> pos(-8000.0f, 8000.0f);
    std::uniform_real_distribution<float> yaw(-180.0f, 179.999f);
    std::uniform_real_distribution<float> pitch(-90.0f, 90.0f);
    const QuantizationSettings s;
    for (int i = 0; i < 20000; ++i) {
        const Pose p{pos(rng), pos(rng), pos(rng), yaw(rng), pitch(rng)};
        for (const float quantum : s.position_quantum) {
            const Pose back =
                dequantize(quantize(p, quantum, s.angle_steps), quantum, s.angle_steps);
            ASSERT_LE(quantization_error(back, p, quantum, s.angle_steps), 0.5 + 1e-3)
                << p.x << " " << p.yaw_deg;
            ASSERT_GE(back.yaw_deg, -180.0f);
            ASSERT_LT(back.yaw_deg, 180.0f);
        }
    }
}

TEST(Quantization, APitchWithinAQuarterTurnQuantizesWithinMaxPitchSteps) {
    // Every step count the settings allow, straight up and down and just inside: never
    // beyond the bound a decoder holds a pitch to, and mostly on it (the bound is tight).
    int on_the_bound = 0;
    for (std::uint32_t steps = 256; steps <= 65536; ++steps) {
        for (const float pitch : {90.0f, -90.0f, 89.999f}) {
            const QuantizedPose q = quantize(Pose{0, 0, 0, 0, pitch}, 1.0f, steps);
            ASSERT_LE(std::abs(q.pitch), max_pitch_steps(steps)) << steps << " " << pitch;
            on_the_bound += std::abs(q.pitch) == max_pitch_steps(steps) ? 1 : 0;
        }
    }
    EXPECT_GT(on_the_bound, 65281 * 3 / 2);
    static_assert(max_pitch_steps(4096) == 1024 && max_pitch_steps(258) == 65 &&
                  max_pitch_steps(257) == 64);
}

TEST(Quantization, ExtentsRoundUpAndErrorsCompareYawAroundTheCircle) {
    EXPECT_EQ(quantize_extent(15.0f, 0.125f), 120u);
    EXPECT_EQ(quantize_extent(15.01f, 0.5f), 31u); // never smaller than the box
    const Pose a{0, 0, 0, 179.99f, 0};
    const Pose b{0, 0, 0, -179.99f, 0};
    EXPECT_LT(quantization_error(a, b, 1.0f, 4096), 1.0); // 0.02 degrees apart, not 360
}

TEST(Quantization, ValidateNamesTheFieldAndTheReason) {
    QuantizationSettings s;
    EXPECT_TRUE(validate(s).empty());
    s.position_quantum = {0.5f, 0.25f, 1.0f};
    s.angle_steps = 100;
    const auto problems = validate(s, "q.");
    ASSERT_EQ(problems.size(), 2u);
    EXPECT_NE(problems[0].find("q.position_quantum_mid"), std::string::npos) << problems[0];
    EXPECT_NE(problems[1].find("q.angle_steps"), std::string::npos) << problems[1];
    s.position_quantum = {std::nanf(""), 1.0f, 1.0f};
    EXPECT_FALSE(validate(s).empty());
    s = QuantizationSettings{};
    s.heard_quantum = 0.5f; // finer than the far tier: hearing would be more precise
    ASSERT_EQ(validate(s).size(), 1u);
    EXPECT_NE(validate(s)[0].find("heard_quantum"), std::string::npos) << validate(s)[0];
    s.heard_quantum = 2048.0f;
    EXPECT_EQ(validate(s).size(), 1u);

    pb::Quantization m;
    m.add_position_quantum(0.125f);
    QuantizationSettings out;
    std::string why;
    EXPECT_FALSE(from_message(m, out, why));
    EXPECT_NE(why.find("expected 3"), std::string::npos) << why;
    to_message(QuantizationSettings{}, m);
    EXPECT_TRUE(from_message(m, out, why)) << why;
    EXPECT_EQ(out.angle_steps, 4096u);
    EXPECT_EQ(out.heard_quantum, 64.0f);
    m.set_heard_quantum(0.0f); // a peer that says nothing of hearing
    EXPECT_FALSE(from_message(m, out, why));
    EXPECT_NE(why.find("heard_quantum"), std::string::npos) << why;
}

TEST(CompactSnapshot, AHeardEntityTravelsCoarseWithoutAnglesAndIsPreciseOnceSeen) {
    const QuantizationSettings q; // heard quantum 64
    SnapshotEncoder enc(q);
    SnapshotDecoder dec(q);
    pb::Snapshot s;
    const Pose exact{1000.0f, -230.0f, 24.0f, 75.0f, -10.0f};
    enc.begin(1, s);
    enc.enter(7, exact, kHalf, 1, kHeardTier, s);
    EXPECT_EQ(s.enter(0).x(), 16); // 1000 / 64, rounded
    EXPECT_EQ(s.enter(0).yaw(), 0u);
    EXPECT_EQ(s.enter(0).pitch(), 0);
    EXPECT_EQ(s.enter(0).half_x(), 1u); // 15 units rounds up to one quantum
    ASSERT_TRUE(dec.apply(through_wire(s)).empty());
    Pose heard = *dec.pose(7);
    EXPECT_EQ(heard.x, 1024.0f);
    EXPECT_EQ(heard.yaw_deg, 0.0f);
    EXPECT_GT(quantization_error(heard, exact, q.position_quantum[0], q.angle_steps), 100.0);

    // Moving and turning within a heard quantum: nothing travels.
    enc.begin(2, s);
    EXPECT_FALSE(enc.update(7, {1010.0f, -230.0f, 24.0f, -120.0f, 30.0f}, kHeardTier, s));
    // Seen: a rebase to the near tier carries the exact pose.
    enc.begin(3, s);
    EXPECT_TRUE(enc.update(7, exact, 0, s));
    EXPECT_EQ(first_entry_fields(s), kFieldRebase);
    ASSERT_TRUE(dec.apply(through_wire(s)).empty());
    EXPECT_LE(quantization_error(*dec.pose(7), exact, q.position_quantum[0], q.angle_steps),
              0.5 + 1e-3);
    // Heard only again: coarse, angles gone.
    enc.begin(4, s);
    EXPECT_TRUE(enc.update(7, exact, kHeardTier, s));
    ASSERT_TRUE(dec.apply(through_wire(s)).empty());
    EXPECT_EQ(dec.pose(7)->yaw_deg, 0.0f);
    EXPECT_EQ(dec.pose(7)->pitch_deg, 0.0f);
    EXPECT_EQ(dec.pose(7)->x, 1024.0f);
}

TEST(CompactSnapshot, AHeardEntityWithAnglesOrAnAuditPoseIsAProblem) {
    const QuantizationSettings q;
    SnapshotDecoder dec(q);
    pb::Snapshot s;
    s.set_server_tick(1);
    pb::EntityState& e = *s.add_enter();
    e.set_id(4);
    e.set_tier(kHeardTier);
    e.set_x(3);
    e.set_yaw(100);
    EXPECT_EQ(kinds(dec.apply(s)).rfind("angles_on_heard_tier", 0), 0u) << kinds(dec.apply(s));
    EXPECT_FALSE(dec.knows(4));

    e.set_yaw(0);
    ASSERT_TRUE(dec.apply(s).empty());
    pb::Snapshot next;
    next.set_server_tick(2);
    add_entry(next, 4, kFieldPitch); // angles for a heard-only entity
    next.add_update_values(5);
    EXPECT_EQ(kinds(dec.apply(next)).rfind("angles_on_heard_tier", 0), 0u);

    pb::Snapshot audited;
    audited.set_server_tick(3);
    pb::AuditPose& a = *audited.add_audit();
    a.set_id(4);
    a.set_x(192.0f);
    double worst = 0.0;
    const auto problems = dec.check_audit(audited, worst);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].kind, "audit_of_heard_entity") << problems[0].detail;
}

TEST(CompactSnapshot, OnlyChangedFieldsTravel) {
    const QuantizationSettings q;
    SnapshotEncoder enc(q);
    pb::Snapshot s;
    enc.begin(1, s);
    enc.enter(7, {100.0f, 200.0f, 24.0f, 90.0f, 0.0f}, kHalf, 0, 0, s);
    enc.enter(9, {0.0f, 0.0f, 24.0f, 0.0f, 0.0f}, kHalf, 0, 0, s);
    EXPECT_EQ(s.enter(0).x(), 800); // 100 / 0.125
    EXPECT_EQ(s.enter(0).half_z(), 224u);

    enc.begin(2, s);
    EXPECT_TRUE(enc.update(7, {110.0f, 200.0f, 24.0f, 90.0f, 0.0f}, 0, s)); // x only
    EXPECT_FALSE(enc.update(9, {0.01f, 0.0f, 24.0f, 0.0f, 0.0f}, 0, s));    // below a quantum
    ASSERT_EQ(s.update_head_size(), 1);
    EXPECT_EQ(s.update_head(0), 7u << 4 | kFieldX); // id 7, mask x, one varint
    EXPECT_EQ(s.update_fields_size(), 0);
    ASSERT_EQ(s.update_values_size(), 1);
    EXPECT_EQ(s.update_values(0), 80);
    // One entry: a 2-byte head (7 << 4 | 1 = 113 < 128, so one byte, and a 2-byte value,
    // plus two tag+length pairs.
    EXPECT_EQ(update_column_bytes(s), 1u + 2 + 2 + 2);
}

TEST(CompactSnapshot, YawDeltasTakeTheShortWayAround) {
    const QuantizationSettings q;
    SnapshotEncoder enc(q);
    SnapshotDecoder dec(q);
    pb::Snapshot s;
    enc.begin(1, s);
    enc.enter(3, {0, 0, 0, 179.9f, 0}, kHalf, 0, 0, s);
    ASSERT_TRUE(dec.apply(through_wire(s)).empty());
    enc.begin(2, s);
    ASSERT_TRUE(enc.update(3, {0, 0, 0, -179.9f, 0}, 0, s));
    EXPECT_EQ(first_entry_fields(s), kFieldYaw);
    EXPECT_LE(std::abs(s.update_values(0)), 3); // 0.2 degrees = 2.3 steps, not 4094
    ASSERT_TRUE(dec.apply(through_wire(s)).empty());
    EXPECT_NEAR(dec.pose(3)->yaw_deg, -179.9f, 0.05f);
}

TEST(CompactSnapshot, AnyYawDeltaLandsOnTheCircleAsTheModuloRuleSays) {
    // The decoder wraps an encoder's deltas without dividing; any other delta (a
    // hostile sender's, up to the int32 limits) must still land where the plain
    // modulo rule puts it.
    const QuantizationSettings q;
    const auto steps = static_cast<std::int64_t>(q.angle_steps);
    SnapshotDecoder dec(q);
    pb::Snapshot s;
    s.set_server_tick(1);
    pb::EntityState& e = *s.add_enter();
    e.set_id(3);
    e.set_yaw(4000);
    ASSERT_TRUE(dec.apply(s).empty());
    std::int64_t yaw = 4000;
    std::mt19937 rng(11);
    const std::array<std::int32_t, 8> edges{std::numeric_limits<std::int32_t>::min(),
                                            std::numeric_limits<std::int32_t>::max(),
                                            -4096,
                                            4095,
                                            -2048,
                                            2047,
                                            -8191,
                                            8191};
    for (int round = 0; round < 3000; ++round) {
        std::int32_t delta = 0;
        switch (round % 4) {
        case 0:
            delta = static_cast<std::int32_t>(rng() % 4096) - 2048;
            break; // an encoder's
        case 1:
            delta = static_cast<std::int32_t>(rng() % 20000) - 10000;
            break;
        case 2:
            delta = static_cast<std::int32_t>(rng());
            break; // anything
        default:
            delta = edges[static_cast<std::size_t>(round / 4) % edges.size()];
            break;
        }
        pb::Snapshot u;
        u.set_server_tick(static_cast<std::uint64_t>(round) + 2);
        add_entry(u, 3, kFieldYaw);
        u.add_update_values(delta);
        ASSERT_TRUE(dec.apply(u).empty()) << "delta " << delta;
        yaw = (((yaw + delta) % steps) + steps) % steps;
        std::int32_t got = -1;
        dec.entities().for_each(
            [&](std::uint32_t, const ReplicaEntity& r) { got = r.quantized.yaw; });
        ASSERT_EQ(got, yaw) << "round " << round << " delta " << delta;
    }
}

TEST(CompactSnapshot, UpdateColumnBytesMatchTheRealEncoder) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::int32_t> big(-5'000'000, 5'000'000);
    for (int round = 0; round < 50; ++round) {
        pb::Snapshot s;
        const int n = static_cast<int>(rng() % 40);
        for (int i = 0; i < n; ++i) {
            s.add_update_head(rng() % (3000u << 4));
            s.add_update_fields(rng() % 64);
            s.add_update_values(big(rng));
            s.add_update_values(static_cast<std::int32_t>(rng() % 200) - 100);
        }
        EXPECT_EQ(update_column_bytes(s), s.ByteSizeLong());
    }
}

/// A server-side world of walking entities: random enters, leaves, tier changes (the
/// heard tier among them), turns and jumps, through the wire, into a decoder that must
/// track it exactly, and keep its count of heard entities equal to a scan's.
TEST(CompactSnapshot, RandomWorldsDecodeWithinHalfAQuantum) {
    QuantizationSettings q;
    q.position_quantum = {0.125f, 0.5f, 2.0f};
    q.angle_steps = 1024;
    SnapshotEncoder enc(q);
    SnapshotDecoder dec(q);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    constexpr std::uint32_t kEntities = 120;
    std::vector<Pose> world(kEntities);
    for (auto& p : world) {
        p = {unit(rng) * 4000.0f, unit(rng) * 4000.0f, unit(rng) * 500.0f, unit(rng) * 180.0f,
             0.0f};
    }
    std::map<std::uint32_t, std::uint8_t> known; // id -> tier
    std::uint64_t updates = 0;
    std::uint64_t update_bytes = 0;
    std::size_t scanned_heard = 0;
    for (std::uint64_t tick = 1; tick <= 400; ++tick) {
        for (auto& p : world) { // walk ~10 units a tick, turn now and then
            p.x += 10.0f * std::cos(p.yaw_deg * 0.0174533f);
            p.y += 10.0f * std::sin(p.yaw_deg * 0.0174533f);
            if (rng() % 10 == 0) {
                p.yaw_deg = std::fmod(p.yaw_deg + 540.0f + unit(rng) * 30.0f, 360.0f) - 180.0f;
            }
            if (rng() % 50 == 0) {
                p.z += unit(rng) * 40.0f;
                p.pitch_deg = unit(rng) * 89.0f;
            }
        }
        pb::Snapshot s;
        enc.begin(tick, s);
        for (std::uint32_t id = 0; id < kEntities; ++id) {
            const bool wanted = rng() % 8 != 0 || known.contains(id);
            const bool drop = known.contains(id) && rng() % 40 == 0;
            if (drop) {
                enc.leave(id, s);
                known.erase(id);
            } else if (wanted && !known.contains(id)) {
                const auto tier = static_cast<std::uint8_t>(rng() % kTiers);
                enc.enter(id, world[id], kHalf, id % 2, tier, s);
                known[id] = tier;
            } else if (wanted) {
                if (rng() % 30 == 0) {
                    known[id] = static_cast<std::uint8_t>(rng() % kTiers);
                }
                updates += enc.update(id, world[id], known[id], s) ? 1 : 0;
            }
        }
        update_bytes += update_column_bytes(s);
        const auto problems = dec.apply(through_wire(s));
        ASSERT_TRUE(problems.empty()) << "tick " << tick << ": " << kinds(problems);
        ASSERT_EQ(dec.size(), known.size());
        std::size_t heard = 0;
        for (const auto& [id, tier] : known) {
            const auto pose = dec.pose(id);
            ASSERT_TRUE(pose.has_value()) << "entity " << id;
            if (tier == kHeardTier) { // a coarse position, no angles
                ++heard;
                Pose flat = world[id];
                flat.yaw_deg = 0.0f;
                flat.pitch_deg = 0.0f;
                ASSERT_LE(quantization_error(*pose, flat, q.heard_quantum, q.angle_steps),
                          0.5 + 1e-3)
                    << "tick " << tick << " heard entity " << id;
                continue;
            }
            const double error =
                quantization_error(*pose, world[id], q.position_quantum[tier], q.angle_steps);
            ASSERT_LE(error, 0.5 + 1e-3) << "tick " << tick << " entity " << id;
        }
        ASSERT_EQ(dec.heard(), heard) << "tick " << tick;
        scanned_heard = std::max(scanned_heard, heard);
    }
    ASSERT_GT(updates, 30000u);
    ASSERT_GT(scanned_heard, 10u); // the heard tier was exercised
    // Walking entities (two ~2-byte position deltas, a 1-byte id step, a 1-byte mask):
    // the columns must stay well under the 24 bytes of a raw full state.
    EXPECT_LT(static_cast<double>(update_bytes) / static_cast<double>(updates), 8.0);
}

TEST(CompactSnapshot, HostileSnapshotsAreReportedNotTrusted) {
    const QuantizationSettings q;
    SnapshotDecoder dec(q);
    pb::Snapshot s;
    auto* e = s.add_enter();
    e->set_id(4);
    s.add_enter()->CopyFrom(*e); // duplicate
    auto* bad_tier = s.add_enter();
    bad_tier->set_id(5);
    bad_tier->set_tier(7);
    s.add_leave(99);
    auto problems = dec.apply(s);
    ASSERT_EQ(problems.size(), 3u) << kinds(problems);
    EXPECT_EQ(problems[0].kind, "duplicate_enter");
    EXPECT_EQ(problems[1].kind, "bad_tier");
    EXPECT_EQ(problems[2].kind, "leave_for_unknown_entity");
    EXPECT_TRUE(dec.knows(4));

    const auto one = [](std::uint32_t id, std::uint32_t fields, std::vector<std::int32_t> values) {
        pb::Snapshot u;
        add_entry(u, id, fields);
        for (const auto v : values) {
            u.add_update_values(v);
        }
        return u;
    };
    EXPECT_EQ(dec.apply(one(8, kFieldX, {1})).at(0).kind, "update_for_unknown_entity");
    EXPECT_EQ(dec.apply(one(4, 0, {})).at(0).kind, "malformed_update");        // empty mask
    EXPECT_EQ(dec.apply(one(4, 1u << 9, {1})).at(0).kind, "malformed_update"); // unknown bit
    EXPECT_EQ(dec.apply(one(4, kFieldX | kFieldY, {1})).at(0).kind, "malformed_update"); // short
    EXPECT_EQ(dec.apply(one(4, kFieldX, {1, 2})).at(0).kind, "malformed_update"); // left over
    EXPECT_EQ(dec.apply(one(4, kFieldRebase, {9, 0, 0, 0, 0, 0})).at(0).kind, "bad_tier");
    EXPECT_EQ(dec.apply(one(4, kFieldX, {2'000'000'000})).at(0).kind, "malformed_update");
    pb::Snapshot twice = one(4, kFieldX, {1});
    twice.add_update_head(0 << 4 | kFieldX); // the same id again
    twice.add_update_values(1);
    EXPECT_EQ(dec.apply(twice).at(0).kind, "malformed_update");
    pb::Snapshot columns = one(4, kFieldX, {1});
    columns.add_update_fields(kFieldPitch); // a mask apart no entry takes
    EXPECT_EQ(dec.apply(columns).at(0).kind, "malformed_update");
    EXPECT_EQ(dec.apply(one(4, kFieldX | kFieldPitch, {1, 0})).size(), 0u); // apart: fine
    // A pitch up to a quarter turn either way, and no further: entering, updated, rebased.
    const std::int32_t quarter = max_pitch_steps(q.angle_steps);
    EXPECT_EQ(dec.apply(one(4, kFieldPitch, {quarter})).size(), 0u);
    EXPECT_EQ(dec.apply(one(4, kFieldPitch, {1})).at(0).kind, "malformed_update");
    EXPECT_EQ(dec.apply(one(4, kFieldPitch, {-2 * quarter - 1})).at(0).kind, "malformed_update");
    EXPECT_EQ(dec.pose(4)->pitch_deg, 90.0f); // the rejected entries changed nothing
    EXPECT_EQ(dec.apply(one(4, kFieldRebase, {0, 0, 0, 0, 0, -quarter - 1})).at(0).kind,
              "malformed_update");
    EXPECT_EQ(dec.apply(one(4, kFieldRebase, {0, 0, 0, 0, 0, -quarter})).size(), 0u);
    pb::Snapshot looking_past_up;
    auto* past = looking_past_up.add_enter();
    past->set_id(6);
    past->set_pitch(quarter + 1);
    EXPECT_EQ(dec.apply(looking_past_up).at(0).kind, "malformed_update");
    EXPECT_FALSE(dec.knows(6));
    past->set_pitch(-quarter);
    pb::Snapshot too_wide;
    too_wide.add_enter()->CopyFrom(*past);
    too_wide.mutable_enter(0)->set_half_x(static_cast<std::uint32_t>(kMaxQuantizedCoordinate) + 1);
    EXPECT_EQ(dec.apply(too_wide).at(0).kind,
              "malformed_update"); // past what quantize_extent sends
    EXPECT_FALSE(dec.knows(6));
    EXPECT_EQ(dec.apply(looking_past_up).size(), 0u);
    pb::Snapshot acked = one(4, kFieldX, {1});
    acked.set_baseline_tick(1); // the other wire's snapshot
    EXPECT_EQ(dec.apply(acked).at(0).kind, "malformed_update");
    pb::Snapshot apart_for_nothing;
    apart_for_nothing.add_update_head(std::uint64_t{4} << 4);
    apart_for_nothing.add_update_fields(kFieldX); // a mask the head could hold
    apart_for_nothing.add_update_values(1);
    EXPECT_EQ(dec.apply(apart_for_nothing).at(0).kind, "malformed_update");

    // An audit that disagrees with the replica by more than half a quantum.
    pb::Snapshot audit;
    auto* a = audit.add_audit();
    a->set_id(4);
    a->set_x(dec.pose(4)->x + 0.2f); // 1.6 quanta of 0.125
    a->set_y(dec.pose(4)->y);
    a->set_z(dec.pose(4)->z);
    a->set_pitch(dec.pose(4)->pitch_deg);
    double worst = 0.0;
    const auto audited = dec.check_audit(audit, worst);
    ASSERT_EQ(audited.size(), 1u);
    EXPECT_EQ(audited[0].kind, "pose_beyond_quantization");
    EXPECT_NEAR(worst, 1.6, 1e-3);
}

} // namespace
} // namespace dsoc::protocol
