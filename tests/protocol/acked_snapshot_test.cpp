#include "dsoc/protocol/acked_snapshot.hpp"

#include "snapshot_wire.hpp"

#include <glm/vec3.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace dsoc::protocol {
namespace {

const std::array<float, 3> kHalf{15.0f, 15.0f, 28.0f};

std::string entity_name(std::uint32_t id) {
    return "entity " + std::to_string(id);
}

/// One entity of the server's world as a test drives it: quantized on every tier.
struct TruthEntity {
    std::uint32_t id = 0;
    Pose pose;
    glm::vec3 velocity{0.0f};
    std::uint8_t tier = 0;
};

QuantizedPose on_tier(const TruthEntity& e, const QuantizationSettings& settings) {
    return quantize(e.pose, settings, e.tier);
}

void encode(AckedSnapshotEncoder& encoder, std::uint64_t tick, std::optional<std::uint64_t> acked,
            const std::vector<TruthEntity>& interest, pb::Snapshot& out) {
    encoder.begin(tick, acked, out);
    for (const TruthEntity& e : interest) {
        encoder.add(e.id, on_tier(e, encoder.settings()), e.tier, 1, kHalf, out);
    }
    encoder.finish(out);
}

TEST(AckedPrediction, RoundsHalvesAwayFromZero) {
    EXPECT_EQ(divide_rounded(5, 2), 3);
    EXPECT_EQ(divide_rounded(-5, 2), -3);
    EXPECT_EQ(divide_rounded(4, 3), 1);
    EXPECT_EQ(divide_rounded(-4, 3), -1);
    EXPECT_EQ(divide_rounded(0, 7), 0);
}

TEST(UpdatePacing, AnEntityIsDueOnceInItsTiersIntervalAndAPacedClientAgrees) {
    for (std::uint8_t tier = 0; tier < kTiers; ++tier) {
        const std::uint64_t interval = update_interval(tier);
        for (std::uint32_t id = 0; id < 9; ++id) {
            std::uint64_t due = 0;
            for (std::uint64_t tick = 1; tick <= 8 * interval; ++tick) {
                const bool now = due_at(id, tier, tick);
                EXPECT_EQ(now, (tick + id) % interval == 0) << "tier " << int{tier} << " id " << id;
                // A client sent every tick: the paced rule since the tick before says the same.
                EXPECT_EQ(now, due_since(id, tier, tick - 1, tick)) << "tick " << tick;
                due += now ? 1 : 0;
            }
            EXPECT_EQ(due, 8u) << "tier " << int{tier} << " id " << id;
        }
    }
}

TEST(AckedPrediction, AnEntityMovingSteadilyIsPredictedExactly) {
    constexpr std::uint32_t kSteps = 4096;
    FrameEntity e;
    e.pose = {100, -50, 8, 10, 0};
    set_motion(e, {40, -20, 8, 4076, 0}, 3, kSteps); // 20, -10, 0 a tick; turning 10 a tick
    EXPECT_EQ(e.velocity[0], 20 * kVelocityScale);
    EXPECT_EQ(e.velocity[1], -10 * kVelocityScale);
    EXPECT_EQ(e.turn_rate, 10 * kVelocityScale); // the shorter way round, across 0
    EXPECT_EQ(predict(e, 4, kSteps), (QuantizedPose{180, -90, 8, 50, 0}));
    e.turn_rate = -10 * kVelocityScale;
    EXPECT_EQ(predict(e, 2, kSteps).yaw, 4086); // wraps below 0
    // A fall: z(k) = -7 k (k + 1) / 2 quanta after k ticks (gravity, 7 quanta a tick a tick),
    // measured over 2 ticks and then over 3, is predicted exactly 4 ticks on.
    const auto fallen = [](std::int32_t k) { return -7 * k * (k + 1) / 2; };
    FrameEntity f;
    f.pose.z = fallen(2);
    set_motion(f, {0, 0, fallen(0), 0, 0}, 2, kSteps);
    EXPECT_EQ(f.fall_rate, 0); // one velocity is no acceleration yet
    f.pose.z = fallen(5);
    set_motion(f, {0, 0, fallen(2), 0, 0}, 3, kSteps);
    EXPECT_EQ(f.fall_rate, -7 * kVelocityScale);
    EXPECT_EQ(predict(f, 4, kSteps).z, fallen(9));
    clear_motion(f);
    EXPECT_EQ(predict(f, 4, kSteps), f.pose);

    e.pose.x = kMaxQuantizedCoordinate; // far out: clamped, never overflowing
    e.velocity[0] = kMaxQuantizedCoordinate;
    EXPECT_EQ(predict(e, kAckedHistory - 1, kSteps).x, kMaxQuantizedCoordinate);
}

// The contract under loss, delay, duplication and reordering: every snapshot the client
// applies leaves it holding exactly the server's frame of that tick (the interest set of
// that tick, no stale entity, no lost leave), and every entity due on that tick exactly at
// its quantized pose; no entity is held longer than its tier's interval.
TEST(AckedSnapshot, TheClientHoldsTheServersFrameWhateverIsLost) {
    for (const std::uint32_t seed : {1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u}) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        QuantizationSettings settings;
        // Odd step counts too: the short way round is then not symmetric.
        settings.angle_steps =
            std::array{4096u, 4096u, 4096u, 4096u, 4095u, 257u, 4096u, 65535u}[seed - 1];
        AckedSnapshotEncoder encoder(settings);
        AckedSnapshotDecoder decoder(settings);
        const float loss = std::array{0.0f, 0.05f, 0.2f, 0.5f, 0.05f, 0.3f, 0.1f, 0.1f}[seed - 1];

        std::vector<TruthEntity> world;
        std::uint32_t next_id = 1;
        for (int i = 0; i < 40; ++i) {
            next_id += 1 + static_cast<std::uint32_t>(rng() % 5);
            world.push_back(
                {next_id, {unit(rng) * 2000.0f, unit(rng) * 2000.0f, 0.0f, 0.0f, 0.0f}});
        }
        std::map<std::uint32_t, bool> wanted;
        struct InFlight {
            int arrives = 0;
            pb::Snapshot snapshot;
        };
        std::deque<InFlight> to_client;
        std::vector<std::pair<int, std::uint64_t>> to_server; // arrival tick, acked tick
        std::optional<std::uint64_t> acked;
        std::map<std::uint64_t, std::vector<TruthEntity>> sent_interest;
        int applied = 0;
        int against_baseline = 0;
        int full = 0;
        int stale = 0;
        for (int tick = 1; tick <= 600; ++tick) {
            // The world moves: steady runs, turns, stops, tier changes, a long outage.
            for (TruthEntity& e : world) {
                if (unit(rng) < 0.05f) {
                    e.velocity = unit(rng) < 0.3f ? glm::vec3(0.0f)
                                                  : glm::vec3(unit(rng) * 10.0f - 5.0f,
                                                              unit(rng) * 10.0f - 5.0f, 0.0f);
                }
                e.pose.x += e.velocity.x;
                e.pose.y += e.velocity.y;
                // Jumps and falls under gravity (the fall rate's case), now and then a
                // teleport.
                e.velocity.z = e.pose.z <= 0.0f && unit(rng) < 0.03f ? 9.0f : e.velocity.z - 0.9f;
                e.pose.z = std::max(0.0f, e.pose.z + e.velocity.z);
                e.velocity.z = e.pose.z <= 0.0f ? 0.0f : e.velocity.z;
                e.pose.z = unit(rng) < 0.005f ? unit(rng) * 400.0f : e.pose.z;
                e.pose.yaw_deg = unit(rng) < 0.3f ? unit(rng) * 359.0f - 180.0f : e.pose.yaw_deg;
                e.pose.pitch_deg = unit(rng) < 0.1f ? unit(rng) * 178.0f - 89.0f : e.pose.pitch_deg;
                if (unit(rng) < 0.02f) {
                    e.tier = static_cast<std::uint8_t>(rng() % kTiers);
                }
                if (unit(rng) < 0.04f || !wanted.contains(e.id)) {
                    wanted[e.id] = unit(rng) < 0.7f;
                }
            }
            std::vector<TruthEntity> interest;
            for (const TruthEntity& e : world) {
                if (wanted[e.id]) {
                    interest.push_back(e);
                }
            }
            for (const auto& [arrives, tick_acked] : to_server) {
                if (arrives == tick) { // acks overtake each other: the newest counts
                    acked = std::max(acked.value_or(0), tick_acked);
                }
            }
            pb::Snapshot snapshot;
            encode(encoder, static_cast<std::uint64_t>(tick), acked, interest, snapshot);
            (snapshot.has_baseline_tick() ? against_baseline : full) += 1;
            sent_interest[static_cast<std::uint64_t>(tick)] = interest;
            const bool outage = tick >= 300 && tick < 340; // longer than the history
            if (!outage && unit(rng) >= loss) {
                const int delay = static_cast<int>(rng() % 4);
                to_client.push_back({tick + delay, through_wire(snapshot)});
                if (unit(rng) < 0.05f) {
                    to_client.push_back({tick + delay + 1, through_wire(snapshot)}); // duplicated
                }
            }
            std::stable_sort(
                to_client.begin(), to_client.end(),
                [](const InFlight& a, const InFlight& b) { return a.arrives < b.arrives; });
            while (!to_client.empty() && to_client.front().arrives <= tick) {
                const pb::Snapshot s = std::move(to_client.front().snapshot);
                to_client.pop_front();
                const auto problems = decoder.apply(s);
                if (!problems.empty()) {
                    ASSERT_EQ(problems.size(), 1u) << kinds(problems);
                    ASSERT_EQ(problems[0].kind, "stale_snapshot") << kinds(problems);
                    ++stale;
                    continue;
                }
                ++applied;
                const DeltaFrame* held = decoder.newest();
                const DeltaFrame* sent = encoder.frame(s.server_tick());
                ASSERT_NE(held, nullptr);
                ASSERT_NE(sent, nullptr);
                ASSERT_EQ(held->entities, sent->entities) << "tick " << s.server_tick();
                const std::vector<TruthEntity>& truth = sent_interest[s.server_tick()];
                ASSERT_EQ(held->entities.size(), truth.size());
                for (std::size_t k = 0; k < truth.size(); ++k) {
                    const FrameEntity& got = held->entities[k];
                    ASSERT_EQ(got.id, truth[k].id);
                    ASSERT_EQ(got.tier, truth[k].tier);
                    // Due on its tick of the interval at the latest, then exact.
                    ASSERT_LT(got.held_ticks, update_interval(got.tier));
                    if ((s.server_tick() + got.id) % update_interval(got.tier) == 0) {
                        ASSERT_EQ(got.held_ticks, 0u) << entity_name(got.id);
                    }
                    if (got.held_ticks == 0) {
                        ASSERT_EQ(got.pose, on_tier(truth[k], settings)) << entity_name(got.id);
                    }
                }
            }
            if (decoder.newest_tick() && unit(rng) >= loss) {
                to_server.emplace_back(tick + 1 + static_cast<int>(rng() % 3),
                                       *decoder.newest_tick());
            }
        }
        EXPECT_GT(applied, 200);
        EXPECT_GT(against_baseline, 300); // deltas, not full snapshots, carried the run
        EXPECT_GE(full, 2);               // the first one and after the outage at least
        EXPECT_GT(stale, 0);              // duplicates and late ones came and changed nothing
    }
}

// A sender out of room leaves entries out (carry_unwritten): the client then holds the
// entity at its prediction (or held, when not due), and the server's frame must say
// exactly that, or a later residual would be coded against a pose the client never had.
// Each snapshot is written twice here, the first time whole and thrown away (restart(), as
// a sender that found it too large does), sometimes against nothing the second time. Once
// nothing is left out, every entity is exact again within its interval.
TEST(AckedSnapshot, EntriesLeftOutLeaveBothEndsTheSameFrame) {
    for (const std::uint32_t seed : {11u, 12u, 13u}) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        const QuantizationSettings settings;
        AckedSnapshotEncoder encoder(settings);
        AckedSnapshotDecoder decoder(settings);
        std::vector<TruthEntity> world;
        for (std::uint32_t id = 1; id <= 60; ++id) {
            world.push_back({id * 3,
                             {unit(rng) * 2000.0f, unit(rng) * 2000.0f, 0.0f, 0.0f, 0.0f},
                             {unit(rng) * 8.0f - 4.0f, unit(rng) * 8.0f - 4.0f, 0.0f},
                             static_cast<std::uint8_t>(rng() % kTiers)});
        }
        std::deque<std::pair<std::uint64_t, std::uint64_t>> acks; // arrival tick, acked tick
        std::optional<std::uint64_t> acked;
        int left_out = 0;
        int applied = 0;
        for (std::uint64_t tick = 1; tick <= 300; ++tick) {
            const bool defer = tick <= 250;
            for (TruthEntity& e : world) {
                if (unit(rng) < 0.1f) { // turns: residuals to write
                    e.velocity = {unit(rng) * 8.0f - 4.0f, unit(rng) * 8.0f - 4.0f, 0.0f};
                }
                e.pose.x += e.velocity.x;
                e.pose.y += e.velocity.y;
                e.pose.yaw_deg = unit(rng) < 0.2f ? unit(rng) * 359.0f - 180.0f : e.pose.yaw_deg;
                e.pose.pitch_deg =
                    unit(rng) < 0.05f ? unit(rng) * 178.0f - 89.0f : e.pose.pitch_deg;
                if (defer && unit(rng) < 0.03f) {
                    e.tier = static_cast<std::uint8_t>(rng() % kTiers); // rebases left out too
                }
            }
            while (!acks.empty() && acks.front().first <= tick) {
                acked = std::max(acked.value_or(0), acks.front().second);
                acks.pop_front();
            }
            pb::Snapshot s;
            encoder.begin(tick, acked, s);
            for (const TruthEntity& e : world) {
                encoder.add(e.id, on_tier(e, settings), e.tier, 1, kHalf, s);
            }
            encoder.leave_the_rest(s);
            encoder.restart(s, defer && unit(rng) < 0.05f);
            for (const TruthEntity& e : world) {
                if (defer && unit(rng) < 0.4f) {
                    if (encoder.carry_unwritten(e.id, s)) {
                        ++left_out;
                        continue;
                    }
                }
                encoder.add(e.id, on_tier(e, settings), e.tier, 1, kHalf, s);
            }
            encoder.finish(s);
            if (unit(rng) < 0.1f) {
                continue; // lost
            }
            const auto problems = decoder.apply(through_wire(s));
            ASSERT_TRUE(problems.empty()) << kinds(problems);
            ++applied;
            const DeltaFrame* held = decoder.newest();
            ASSERT_EQ(held->entities, encoder.frame(tick)->entities) << "tick " << tick;
            acks.emplace_back(tick + 1 + rng() % 3, tick);
            if (tick >= 270) { // nothing left out for 20 ticks: every due entity exact
                for (std::size_t k = 0; k < world.size(); ++k) {
                    const FrameEntity& got = held->entities[k];
                    if (got.held_ticks == 0) {
                        ASSERT_EQ(got.pose, on_tier(world[k], settings)) << entity_name(got.id);
                    }
                }
            }
        }
        EXPECT_GT(left_out, 2000);
        EXPECT_GT(applied, 200);
    }
}

// A client the server paces (snapshots every 2nd, 3rd or 4th tick) still has every
// coarse-tier entity due within its interval: with a rule of due ticks alone, an entity
// whose ticks the pace never meets would never be updated.
TEST(AckedSnapshot, APacedClientGetsEveryCoarseEntityWithinItsInterval) {
    const QuantizationSettings settings;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> step(-6.0f, 6.0f);
    for (const std::uint64_t pace : {2u, 3u, 4u}) {
        SCOPED_TRACE("every " + std::to_string(pace) + " ticks");
        AckedSnapshotEncoder encoder(settings);
        AckedSnapshotDecoder decoder(settings);
        std::vector<TruthEntity> interest;
        for (std::uint32_t id = 1; id <= 12; ++id) { // every residue on every coarse tier
            interest.push_back({id,
                                {100.0f * id, 0.0f, 0.0f, 0.0f, 0.0f},
                                {},
                                static_cast<std::uint8_t>(1 + (id - 1) / 4)});
        }
        std::optional<std::uint64_t> acked;
        int exact = 0;
        for (std::uint64_t tick = 1; tick <= 200; ++tick) {
            for (TruthEntity& e : interest) { // a random walk: never predicted exactly
                e.pose.x += step(rng) * 20.0f;
                e.pose.y += step(rng) * 20.0f;
            }
            if (tick % pace != 0) {
                continue; // paced: nothing sent this tick
            }
            pb::Snapshot s;
            encode(encoder, tick, acked, interest, s);
            ASSERT_TRUE(decoder.apply(through_wire(s)).empty());
            acked = tick;
            for (std::size_t k = 0; k < interest.size(); ++k) {
                const FrameEntity& got = decoder.newest()->entities[k];
                const std::uint64_t interval = update_interval(got.tier);
                ASSERT_LT(got.held_ticks, interval) << entity_name(got.id);
                if (pace >= interval) { // every span of `pace` ticks meets its due tick
                    ASSERT_EQ(got.held_ticks, 0u) << entity_name(got.id);
                }
                if (got.held_ticks == 0) {
                    ASSERT_EQ(got.pose, on_tier(interest[k], settings)) << entity_name(got.id);
                    ++exact;
                }
            }
        }
        EXPECT_GT(exact, static_cast<int>(200 / pace * 12 / 2));
    }
}

// A coarse-tier entity moving steadily costs nothing on the ticks it is due either: its
// prediction spans every tick since its pose was set, held ticks included; and the
// decoder's pose() of a held entity is where it is now, not where it was set.
TEST(AckedSnapshot, AHeldEntityIsPredictedOverEveryTickSinceItsPoseWasSet) {
    const QuantizationSettings settings;
    for (const std::uint8_t tier : {std::uint8_t{1}, std::uint8_t{2}, kHeardTier}) {
        SCOPED_TRACE("tier " + std::to_string(tier));
        AckedSnapshotEncoder encoder(settings);
        AckedSnapshotDecoder decoder(settings);
        const float step = 3.0f * settings.quantum(tier); // whole quanta a tick: exact
        std::vector<TruthEntity> interest{{5, {0.0f, 0.0f, 0.0f, 0.0f, 0.0f}, {}, tier}};
        std::optional<std::uint64_t> acked;
        std::uint32_t late_entries = 0;
        int held = 0;
        for (std::uint64_t tick = 1; tick <= 60; ++tick) {
            interest[0].pose.x += step;
            pb::Snapshot s;
            encode(encoder, tick, acked, interest, s);
            ASSERT_TRUE(decoder.apply(through_wire(s)).empty());
            acked = tick;
            if (tick > 20) {
                late_entries += static_cast<std::uint32_t>(s.update_head_size());
                held += decoder.newest()->entities[0].held_ticks > 0 ? 1 : 0;
                EXPECT_NEAR(decoder.pose(5)->x, interest[0].pose.x, 0.5f * settings.quantum(tier))
                    << "tick " << tick;
            }
        }
        EXPECT_EQ(late_entries, 0u);
        EXPECT_GT(held, 15); // most of those ticks it was held, not due
    }
}

TEST(AckedSnapshot, SteadyMotionCostsNoUpdateEntries) {
    const QuantizationSettings settings;
    AckedSnapshotEncoder encoder(settings);
    AckedSnapshotDecoder decoder(settings);
    // A mover turning steadily, one standing still, one far up the id range.
    std::vector<TruthEntity> interest{{7, {0.0f, 0.0f, 0.0f, 90.0f, 0.0f}},
                                      {9, {500.0f, 0.0f, 0.0f, 0.0f, 0.0f}},
                                      {0xfffffff0u, {-500.0f, 0.0f, 0.0f, 0.0f, 0.0f}}};
    std::optional<std::uint64_t> acked;
    std::uint32_t late_entries = 0;
    std::uint32_t late_entries_of_7 = 0;
    std::uint32_t late_moved = 0;
    for (std::uint64_t tick = 1; tick <= 40; ++tick) {
        interest[0].pose.x += 2.5f; // 20 quanta a tick
        interest[0].pose.y -= 1.25f;
        interest[0].pose.yaw_deg -= 360.0f / 4096.0f * 3.0f; // 3 steps a tick
        interest[2].pose.x += tick % 3 == 0 ? 1.0f : 0.0f;   // unsteady: entries
        pb::Snapshot s;
        encoder.begin(tick, acked, s);
        for (const TruthEntity& e : interest) {
            encoder.add(e.id, on_tier(e, settings), e.tier, 1, kHalf, s);
        }
        const AckedSnapshotCounts counts = encoder.finish(s);
        ASSERT_TRUE(decoder.apply(through_wire(s)).empty());
        if (tick > 10) {
            late_entries += counts.entries;
            late_moved += counts.moved;
            std::uint64_t id = 0;
            for (int i = 0; i < s.update_head_size(); ++i) {
                id = i == 0 ? s.update_head(i) >> 4 : id + (s.update_head(i) >> 4);
                late_entries_of_7 += id == 7 ? 1 : 0;
            }
        }
        if (tick >= 4) {
            acked = tick - 3; // three ticks of round trip
        }
    }
    // Entity 7 is predicted exactly once it has a velocity; only the far one's uneven
    // steps cost entries. Both moved since the baseline on every one of those ticks.
    EXPECT_EQ(late_entries_of_7, 0u);
    EXPECT_GT(late_entries, 0u);
    EXPECT_LE(late_entries, 30u);
    EXPECT_EQ(late_moved, 60u);
    EXPECT_NEAR(decoder.pose(7)->x, 100.0f, 1e-3f);
    EXPECT_NEAR(decoder.pose(7)->yaw_deg, 90.0f - 40 * 3 * 360.0f / 4096.0f, 1e-3f);
    EXPECT_NEAR(decoder.pose(0xfffffff0u)->x, -487.0f, 1e-3f);
}

TEST(AckedSnapshot, EachEndForgetsTheFramesNoSnapshotWillBeCodedAgainst) {
    const QuantizationSettings settings;
    // Two servers fed the same: one acknowledged as a server is, one that breaks the
    // promise that baselines never go back.
    AckedSnapshotEncoder server(settings);
    AckedSnapshotEncoder unruly(settings);
    AckedSnapshotDecoder client(settings);
    std::vector<TruthEntity> interest{{3, {1.0f, 2.0f, 3.0f, 0.0f, 0.0f}},
                                      {9, {50.0f, 0.0f, 0.0f, 0.0f, 0.0f}}};
    pb::Snapshot s;
    pb::Snapshot ignored;
    for (std::uint64_t tick = 1; tick <= 3; ++tick) {
        interest[0].pose.x += 2.0f;
        encode(server, tick, std::nullopt, interest, s);
        encode(unruly, tick, std::nullopt, interest, ignored);
        ASSERT_TRUE(client.apply(through_wire(s)).empty());
    }
    interest[0].pose.x += 2.0f;
    encode(server, 4, 2, interest, s); // the server forgets frame 1
    encode(unruly, 4, std::nullopt, interest, ignored);
    EXPECT_EQ(server.frame(1), nullptr);
    EXPECT_NE(server.frame(2), nullptr);
    ASSERT_TRUE(client.apply(through_wire(s)).empty()); // so does the client

    interest[0].pose.x += 2.0f;
    encode(unruly, 5, 1, interest, s);
    ASSERT_EQ(s.baseline_tick(), 1u);
    const auto problems = client.apply(through_wire(s));
    ASSERT_EQ(problems.size(), 1u) << kinds(problems);
    EXPECT_EQ(problems[0].kind, "baseline_missing");
    encode(unruly, 6, 2, interest, s); // the baseline the client last saw: still held
    EXPECT_TRUE(client.apply(through_wire(s)).empty());
    EXPECT_EQ(client.newest()->entities, unruly.frame(6)->entities);
}

TEST(FrameRing, AFrameIsBuiltInTheMemoryForgottenMostRecently) {
    FrameRing ring;
    const FrameEntity* memory[4] = {};
    for (std::uint64_t tick = 1; tick <= 4; ++tick) {
        DeltaFrame& f = ring.start(tick);
        f.entities.resize(100 * tick); // each its own buffer
        memory[tick - 1] = f.entities.data();
        ring.commit();
    }
    ring.forget_older_than(3); // frames 1 and 2: 2 is the newer, so the warmer
    EXPECT_EQ(ring.find(2), nullptr);
    EXPECT_NE(ring.find(3), nullptr);
    DeltaFrame& next = ring.start(5);
    EXPECT_TRUE(next.entities.empty());
    EXPECT_EQ(next.entities.data(), memory[1]);
    ring.commit();
    EXPECT_EQ(ring.start(6).entities.data(), memory[0]);
    EXPECT_EQ(ring.find(5)->tick, 5u);
    EXPECT_EQ(ring.find(3)->entities.data(), memory[2]); // held frames keep theirs
}

TEST(FrameRing, AFrameStartedWithoutMemoryToReuseHasRoomForTheNewestAtOnce) {
    // No acknowledgement between two frames: nothing was forgotten, nothing is spare.
    FrameRing ring;
    ring.start(1).entities.resize(440);
    ring.commit();
    DeltaFrame& next = ring.start(2);
    EXPECT_TRUE(next.entities.empty());
    EXPECT_GE(next.entities.capacity(), 440u + FrameRing::kSlackEntities);
    const FrameEntity* room = next.entities.data();
    next.entities.resize(440 + FrameRing::kSlackEntities);
    EXPECT_EQ(next.entities.data(), room) << "filled without growing";
    ring.commit();
    EXPECT_EQ(ring.find(2)->entities.data(), room) << "and kept at that size";
}

TEST(FrameRing, MemoryFollowsTheFramesDownAfterAPeak) {
    // A frame of 1,000 entities, forgotten, so that the next frame (of 10) is built in
    // its buffer; then frames of 10, each acknowledged at once: the peak's memory is
    // given back, not kept for the connection's life.
    FrameRing ring;
    ring.start(1).entities.resize(1000);
    ring.commit();
    ring.forget_older_than(2);
    DeltaFrame& small = ring.start(2);
    EXPECT_GE(small.entities.capacity(), 1000u) << "built in the peak's buffer";
    small.entities.resize(10);
    ring.commit();
    EXPECT_LE(ring.find(2)->entities.capacity(), 2 * 10 + FrameRing::kSlackEntities)
        << "committed at its own size";
    for (std::uint64_t tick = 3; tick <= 2 * kAckedHistory; ++tick) {
        ring.forget_older_than(tick - 1);
        ring.start(tick).entities.resize(10);
        ring.commit();
    }
    // Two frames held, the one being built and two spares, each within the bound.
    EXPECT_LE(ring.capacity(), 5 * (2 * 10 + FrameRing::kSlackEntities));
    // A buffer within twice the need is still reused (no allocation per tick).
    const FrameEntity* forgotten = ring.find(2 * kAckedHistory - 1)->entities.data();
    ring.forget_older_than(2 * kAckedHistory);
    EXPECT_EQ(ring.start(2 * kAckedHistory + 1).entities.data(), forgotten);
}

TEST(AckedSnapshot, TheSnapshotMessageGivesBackAPeakOfEnters) {
    // A first snapshot of 300 enters, then acknowledged snapshots in which nothing
    // enters: the message keeps the enters' memory for one snapshot like the first,
    // then gives it back (buffer_room.hpp) rather than holding the peak for the
    // connection's life.
    const QuantizationSettings settings;
    AckedSnapshotEncoder encoder(settings);
    std::vector<TruthEntity> world(300);
    for (std::uint32_t i = 0; i < world.size(); ++i) {
        world[i].id = i + 1;
        world[i].pose.x = static_cast<float>(i);
    }
    pb::Snapshot out;
    encode(encoder, 1, std::nullopt, world, out);
    ASSERT_EQ(out.enter_size(), 300);
    encode(encoder, 2, 1, world, out);
    EXPECT_EQ(out.enter_size(), 0);
    EXPECT_GE(out.enter().ClearedCount(), 300) << "kept after one snapshot";
    encode(encoder, 3, 2, world, out);
    EXPECT_EQ(out.enter_size(), 0);
    EXPECT_EQ(out.enter().Capacity(), 0) << "then given back";
}

TEST(AckedSnapshot, AnAcknowledgementOlderThanTheHistoryGetsAFullSnapshot) {
    const QuantizationSettings settings;
    AckedSnapshotEncoder encoder(settings);
    const std::vector<TruthEntity> interest{{3, {1.0f, 2.0f, 3.0f, 0.0f, 0.0f}}};
    pb::Snapshot s;
    for (std::uint64_t tick = 1; tick <= 40; ++tick) {
        encode(encoder, tick, std::nullopt, interest, s);
    }
    encode(encoder, 41, 41 - (kAckedHistory - 1), interest, s); // the oldest frame held
    EXPECT_TRUE(s.has_baseline_tick());
    EXPECT_EQ(s.enter_size(), 0);
    encode(encoder, 42, 42 - kAckedHistory, interest, s); // just replaced
    EXPECT_FALSE(s.has_baseline_tick());
    EXPECT_EQ(s.enter_size(), 1);
    encode(encoder, 43, 43, interest, s); // not older than the snapshot: never
    EXPECT_FALSE(s.has_baseline_tick());
}

/// A client holding the frame of tick 2, for the hostile cases: entities 4 and 6 on
/// the near tier, 8 on tier 1 (not due at tick 3), 13 heard (due at tick 3).
struct HostileFixture : ::testing::Test {
    QuantizationSettings settings;
    AckedSnapshotEncoder encoder{settings};
    AckedSnapshotDecoder decoder{settings};
    std::vector<TruthEntity> interest{{4, {1.0f, 2.0f, 3.0f, 0.0f, 0.0f}},
                                      {6, {8.0f, 2.0f, 3.0f, 0.0f, 0.0f}},
                                      {8, {16.0f, 2.0f, 3.0f, 0.0f, 0.0f}, {}, 1},
                                      {13, {256.0f, 2.0f, 3.0f, 0.0f, 0.0f}, {}, kHeardTier}};

    void SetUp() override {
        pb::Snapshot s;
        encode(encoder, 1, std::nullopt, interest, s);
        ASSERT_TRUE(decoder.apply(through_wire(s)).empty());
        interest[0].pose.x += 4.0f;
        encode(encoder, 2, 1, interest, s);
        ASSERT_TRUE(decoder.apply(through_wire(s)).empty());
    }
    /// A valid snapshot of tick 3 against tick 2, for a test to break.
    pb::Snapshot next() {
        pb::Snapshot s;
        interest[1].pose.y += 1.0f;
        encode(encoder, 3, 2, interest, s);
        return s;
    }
    /// Applies `s`; expects it rejected for `kind` with the client still at tick 2.
    void expect_rejected(const pb::Snapshot& s, const std::string& kind) {
        const DeltaFrame before = *decoder.newest();
        const auto problems = decoder.apply(through_wire(s));
        ASSERT_FALSE(problems.empty());
        EXPECT_EQ(problems[0].kind, kind) << kinds(problems);
        EXPECT_FALSE(problems[0].detail.empty());
        EXPECT_EQ(decoder.newest_tick(), 2u);
        EXPECT_EQ(decoder.newest()->entities, before.entities);
    }
};

TEST_F(HostileFixture, TheValidSnapshotApplies) {
    const pb::Snapshot s = next();
    EXPECT_TRUE(s.has_baseline_tick());
    EXPECT_TRUE(decoder.apply(through_wire(s)).empty());
    EXPECT_EQ(decoder.newest()->entities, encoder.frame(3)->entities);
}

TEST_F(HostileFixture, StaleAndDuplicateSnapshotsAreRejected) {
    pb::Snapshot s = next();
    s.set_server_tick(2);
    expect_rejected(s, "stale_snapshot");
    s.set_server_tick(1);
    expect_rejected(s, "stale_snapshot");
}

TEST_F(HostileFixture, EntriesMustFitTheEntitysTier) {
    pb::Snapshot s = next();
    s.add_update_head(2u << 4 | kFieldX); // entity 8, after 6: tier 1 is not due at tick 3
    s.add_update_values(5);
    expect_rejected(s, "malformed_update");
    s = next();
    s.add_update_head(7u << 4 | kFieldYaw); // entity 13, heard: no angles
    s.add_update_values(5);
    expect_rejected(s, "angles_on_heard_tier");
}

TEST_F(HostileFixture, EntersAndLeavesMustIncrease) {
    pb::Snapshot s = next();
    s.add_enter()->set_id(20);
    s.add_enter()->set_id(19);
    expect_rejected(s, "malformed_update");
    s = next();
    s.add_leave(13);
    s.add_leave(8);
    expect_rejected(s, "malformed_update");
}

TEST_F(HostileFixture, AFrameTheClientDoesNotHoldIsRejected) {
    pb::Snapshot s = next();
    s.set_baseline_tick(1000);
    expect_rejected(s, "baseline_missing");
    s.set_baseline_tick(3); // itself
    expect_rejected(s, "baseline_missing");
    s.set_server_tick(2 + kAckedHistory); // older than the history
    s.set_baseline_tick(2);
    expect_rejected(s, "baseline_missing");
}

TEST_F(HostileFixture, EntersLeavesAndEntriesMustMeetTheBaseline) {
    pb::Snapshot s = next();
    pb::EntityState& again = *s.add_enter();
    again.set_id(6);
    expect_rejected(s, "duplicate_enter");
    s = next();
    s.add_leave(5);
    expect_rejected(s, "leave_for_unknown_entity");
    s = next();
    s.add_leave(6); // and its update entry stays
    expect_rejected(s, "update_for_unknown_entity");
    s = next();
    s.set_update_head(0, 5u << 4 | (s.update_head(0) & 15u)); // entity 5, then 7
    expect_rejected(s, "update_for_unknown_entity");
}

TEST_F(HostileFixture, MalformedEntriesAreRejected) {
    // The first entry's mask apart (low bits 0), then made bad.
    const auto mask_apart = [](pb::Snapshot& s, std::uint32_t fields) {
        s.set_update_head(0, s.update_head(0) & ~std::uint64_t{15});
        s.add_update_fields(fields);
    };
    pb::Snapshot s = next();
    ASSERT_EQ(s.update_head_size(), 2); // 4 is not where its velocity says, 6 moved
    ASSERT_EQ(s.update_fields_size(), 0);
    mask_apart(s, 64);
    expect_rejected(s, "malformed_update");
    s = next();
    mask_apart(s, kFieldX | kFieldRebase);
    expect_rejected(s, "malformed_update");
    s = next();
    s.set_update_head(0, s.update_head(0) & ~std::uint64_t{15}); // no mask apart to take
    expect_rejected(s, "malformed_update");
    s = next();
    s.add_update_fields(kFieldX); // a mask apart no entry takes
    expect_rejected(s, "malformed_update");
    s = next();
    s.add_update_values(1);
    expect_rejected(s, "malformed_update");
    s = next();
    s.set_update_head(1, 0); // entity 6 becomes 4 again
    expect_rejected(s, "malformed_update");
    s = next();
    s.set_update_values(0, std::numeric_limits<std::int32_t>::max());
    expect_rejected(s, "malformed_update");
    s = next();
    mask_apart(s, kFieldRebase);
    for (const int v : {0, 0, 0, 0, 0}) { // six values: the tier is the first one's
        s.add_update_values(v);
    }
    expect_rejected(s, "bad_tier");
    s = next();
    mask_apart(s, kFieldRebase);
    s.set_update_values(0, 0); // tier 0, then x beyond the range
    s.set_update_values(1, kMaxQuantizedCoordinate + 1);
    for (const int v : {0, 0, 0, 0, 0}) {
        s.add_update_values(v);
    }
    expect_rejected(s, "malformed_update");
    s = next();
    pb::EntityState& far = *s.add_enter();
    far.set_id(9);
    far.set_y(-kMaxQuantizedCoordinate - 1);
    expect_rejected(s, "malformed_update");
    s = next();
    pb::EntityState& huge = *s.add_enter(); // no encoder sends a half extent past 2^30
    huge.set_id(9);
    huge.set_half_z(static_cast<std::uint32_t>(kMaxQuantizedCoordinate) + 1);
    expect_rejected(s, "malformed_update");
    huge.set_half_z(static_cast<std::uint32_t>(kMaxQuantizedCoordinate)); // on the bound
    EXPECT_TRUE(decoder.apply(through_wire(s)).empty());
}

TEST_F(HostileFixture, APitchBeyondAQuarterTurnIsRejected) {
    // Entering, updated or rebased: what no pose within [-90, 90] degrees quantizes to.
    const std::int32_t quarter = max_pitch_steps(settings.angle_steps);
    pb::Snapshot s = next();
    pb::EntityState& up = *s.add_enter();
    up.set_id(9);
    up.set_pitch(quarter + 1);
    expect_rejected(s, "malformed_update");
    s = next();
    s.set_update_head(1, s.update_head(1) & ~std::uint64_t{15}); // entity 6's mask apart
    s.add_update_fields(kFieldY | kFieldPitch);
    s.add_update_values(-quarter - 1);
    expect_rejected(s, "malformed_update");
    s = next();
    s.set_update_head(0, s.update_head(0) & ~std::uint64_t{15}); // entity 4 rebased
    s.add_update_fields(kFieldRebase);
    s.clear_update_values();
    for (const std::int32_t v : {0, 0, 0, 0, 0, quarter + 1, 1}) { // then entity 6's y
        s.add_update_values(v);
    }
    expect_rejected(s, "malformed_update");
    // On the bound is a pitch, and the same snapshots apply.
    s.set_update_values(5, quarter);
    EXPECT_TRUE(decoder.apply(through_wire(s)).empty());
    EXPECT_EQ(decoder.find(4)->pose.pitch, quarter);
}

} // namespace
} // namespace dsoc::protocol
