// SnapshotPacer: a UDP client whose acknowledgements keep their usual age gets every
// tick's snapshot, however far away it is; one whose acknowledgements age past that
// (lagging) gets every 2nd tick, and past the unacked window (behind) every 4th, each
// until the age falls back; and a round trip that grew for good becomes the new usual.

#include "dsoc/server/snapshot_pacer.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

namespace dsoc::server {
namespace {

using Pace = SnapshotPacer::Pace;

/// Offers ticks from..to (inclusive) with the client acknowledging what it was sent
/// `delay` ticks after it was sent (never, for a delay of nullopt); returns the ticks
/// sent. `sent` and `acked` carry over between calls.
struct Client {
    SnapshotPacer pacer{30};
    std::vector<std::uint64_t> sent;
    std::optional<std::uint64_t> acked;

    std::vector<std::uint64_t> run(std::uint64_t from, std::uint64_t to,
                                   std::optional<std::uint64_t> delay) {
        std::vector<std::uint64_t> now;
        for (std::uint64_t tick = from; tick <= to; ++tick) {
            if (delay) { // the newest snapshot sent at least `delay` ticks ago is acknowledged
                for (auto it = sent.rbegin(); it != sent.rend(); ++it) {
                    if (*it + *delay <= tick) {
                        acked = std::max(acked.value_or(0), *it);
                        break;
                    }
                }
            }
            if (pacer.offer(tick, acked)) {
                sent.push_back(tick);
                now.push_back(tick);
            }
        }
        return now;
    }
};

std::uint64_t widest_gap(const std::vector<std::uint64_t>& ticks) {
    std::uint64_t widest = 0;
    for (std::size_t i = 1; i < ticks.size(); ++i) {
        widest = std::max(widest, ticks[i] - ticks[i - 1]);
    }
    return widest;
}

TEST(SnapshotPacer, AClientThatKeepsUpGetsEveryTickNearOrFar) {
    for (const std::uint64_t delay : {1u, 2u, 10u}) { // 10 ticks: a 333 ms round trip
        Client c;
        const auto sent = c.run(1, 300, delay);
        EXPECT_EQ(sent.size(), 300u) << "delay " << delay;
        EXPECT_EQ(c.pacer.pace(), Pace::full);
        EXPECT_EQ(c.pacer.skipped_lagging() + c.pacer.skipped_behind(), 0u);
    }
}

TEST(SnapshotPacer, ALaggingClientGetsEverySecondTickUntilItCatchesUp) {
    Client c;
    ASSERT_EQ(c.run(1, 200, 2).size(), 200u);
    // Its acknowledgements fall 6 ticks behind for a second (a reader that cannot keep
    // up): past the margin, short of the unacked window.
    const auto lagging = c.run(201, 230, 6);
    EXPECT_EQ(c.pacer.pace(), Pace::lagging);
    EXPECT_LT(lagging.size(), 20u);
    EXPECT_GT(lagging.size(), 13u);
    EXPECT_EQ(widest_gap(lagging), SnapshotPacer::kLaggingInterval);
    EXPECT_GT(c.pacer.skipped_lagging(), 10u);
    EXPECT_EQ(c.pacer.skipped_behind(), 0u);
    // It catches up: every tick again at once.
    const auto caught_up = c.run(231, 260, 2);
    EXPECT_EQ(c.pacer.pace(), Pace::full);
    EXPECT_GE(caught_up.size(), 28u);
}

TEST(SnapshotPacer, AClientThatAcknowledgesNothingGetsEveryFourthTickPastTheWindow) {
    Client c;
    ASSERT_EQ(c.run(1, 100, 2).size(), 100u);
    const auto silent = c.run(101, 200, std::nullopt);
    EXPECT_EQ(c.pacer.pace(), Pace::behind);
    const std::uint64_t window = c.pacer.unacked_window();
    EXPECT_EQ(window, 15u); // half a second at 30 Hz
    std::size_t past_window = 0;
    for (std::size_t i = 1; i < silent.size(); ++i) {
        if (silent[i] > 100 + window + 1) {
            EXPECT_EQ(silent[i] - silent[i - 1], SnapshotPacer::kBehindInterval) << silent[i];
            ++past_window;
        }
    }
    EXPECT_GT(past_window, 15u);
    EXPECT_GT(c.pacer.skipped_behind(), 50u);
    // Silent from its first tick (here 1000): the age counts from that tick, and without
    // an acknowledgement the client is never lagging, only behind once past the window.
    SnapshotPacer fresh(30);
    std::vector<std::uint64_t> sent;
    for (std::uint64_t tick = 1000; tick < 1100; ++tick) {
        if (fresh.offer(tick, std::nullopt)) {
            sent.push_back(tick);
        }
    }
    std::vector<std::uint64_t> expected;
    for (std::uint64_t tick = 1000; tick <= 1000 + window; ++tick) {
        expected.push_back(tick); // within the window: every tick
    }
    for (std::uint64_t tick = expected.back() + SnapshotPacer::kBehindInterval; tick < 1100;
         tick += SnapshotPacer::kBehindInterval) {
        expected.push_back(tick);
    }
    EXPECT_EQ(sent, expected);
    EXPECT_EQ(fresh.skipped_lagging(), 0u);
}

TEST(SnapshotPacer, TheUsualAgeSpansTwoWindowsSoARollOverForgetsNothingRecent) {
    // Acknowledged a tick after sending until the middle of the second window, then 8
    // ticks late on: after the roll-over into the third window, whose ages are all late,
    // the least age of the window before still counts, so the client is still lagging.
    Client c;
    const std::uint64_t window = c.pacer.base_window();
    ASSERT_EQ(window, 300u); // 10 s at 30 Hz
    ASSERT_EQ(c.run(1, window + window / 2, 1).size(), window + window / 2);
    (void)c.run(window + window / 2 + 1, 2 * window + 20, 8);
    EXPECT_EQ(c.pacer.pace(), Pace::lagging);
}

TEST(SnapshotPacer, ARoundTripThatGrewForGoodBecomesTheUsualOne) {
    Client c;
    const std::uint64_t window = c.pacer.base_window();
    ASSERT_EQ(c.run(1, 200, 1).size(), 200u);
    // The route got longer: 8 ticks from now on. Lagging at first, for at least a
    // window (a lag of seconds is not taken for the usual age); within two windows of the
    // least age the new round trip is the usual one and every tick goes again.
    const auto first = c.run(201, 200 + window, 8);
    EXPECT_EQ(c.pacer.pace(), Pace::lagging);
    EXPECT_LT(first.size(), window * 3 / 4);
    EXPECT_GT(c.pacer.skipped_lagging(), window / 4);
    (void)c.run(201 + window, 200 + 2 * window + 8, 8);
    const auto later = c.run(201 + 2 * window + 8, 260 + 2 * window + 8, 8);
    EXPECT_EQ(c.pacer.pace(), Pace::full);
    EXPECT_EQ(later.size(), 60u);
}

TEST(SnapshotPacer, TheWindowIsHalfASecondOfTicksWithinItsBounds) {
    EXPECT_EQ(SnapshotPacer::unacked_window_at(30), 15u);
    EXPECT_EQ(SnapshotPacer::unacked_window_at(10), 8u);
    EXPECT_EQ(SnapshotPacer::unacked_window_at(128), 27u);
}

} // namespace
} // namespace dsoc::server
