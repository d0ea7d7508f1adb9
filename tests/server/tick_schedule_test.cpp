#include "dsoc/server/tick_schedule.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace dsoc::server {
namespace {

using std::chrono::milliseconds;
using Clock = TickSchedule::Clock;

// Runs a tick loop on a simulated clock: each tick takes cost(i) ms of work; returns
// the start time of every tick (ms from t0) and the skipped and late counts.
struct LoopRun {
    std::vector<long> starts;
    std::uint64_t skipped = 0;
    std::uint64_t late = 0;
    long last_due = 0; ///< ms from t0: the grid point the last tick ran for
};
template <class Cost>
LoopRun simulate(long period_ms, long until_ms, Cost cost) {
    const Clock::time_point t0{};
    TickSchedule schedule(t0, milliseconds(period_ms));
    Clock::time_point now = t0;
    LoopRun run;
    while (now - t0 < milliseconds(until_ms)) {
        run.skipped += schedule.skip_missed(now);
        now = std::max(now, schedule.next_due()); // the timer fires (at once when past due)
        run.late += schedule.start_tick(now) ? 1 : 0;
        run.starts.push_back(std::chrono::duration_cast<milliseconds>(now - t0).count());
        now += milliseconds(cost(run.starts.size() - 1));
    }
    run.last_due =
        std::chrono::duration_cast<milliseconds>(schedule.next_due() - t0).count() - period_ms;
    return run;
}

TEST(TickSchedule, OnTimeTicksFollowTheGridWithoutDrift) {
    const LoopRun run = simulate(10, 1000, [](std::size_t) { return 3L; });
    ASSERT_EQ(run.starts.size(), 100u);
    for (std::size_t i = 0; i < run.starts.size(); ++i) {
        EXPECT_EQ(run.starts[i], 10L * static_cast<long>(i + 1)) << i;
    }
    EXPECT_EQ(run.skipped, 0u);
    EXPECT_EQ(run.late, 0u);
}

// One 95 ms tick in a 10 ms loop: the old loop ran the ~9 missed ticks back to back
// afterwards; now they are dropped and counted, one tick runs at once, and the
// next ones are back on the grid.
TEST(TickSchedule, AnOverloadDropsTheMissedTicksInsteadOfBursting) {
    const LoopRun run = simulate(10, 300, [](std::size_t i) { return i == 4 ? 95L : 2L; });
    // Tick 4 starts at 50 and ends at 145: ticks due at 60..140 are missed.
    EXPECT_EQ(run.starts[4], 50);
    EXPECT_EQ(run.starts[5], 145); // in place of the one due at 140, at once
    EXPECT_EQ(run.starts[6], 150); // back on the grid
    EXPECT_EQ(run.starts[7], 160);
    EXPECT_EQ(run.skipped, 8u); // due at 60, 70, ..., 130
    EXPECT_EQ(run.late, 1u);
    for (std::size_t i = 1; i < run.starts.size(); ++i) {
        EXPECT_GE(run.starts[i] - run.starts[i - 1], 5) << "burst at tick " << i;
    }
}

// Ticks that always take 1.5 periods: every other grid point is dropped, and the
// loop never falls further behind (the skipped count grows with time, the delay
// does not).
TEST(TickSchedule, SustainedOverloadKeepsAFixedDelay) {
    const LoopRun run = simulate(10, 3000, [](std::size_t) { return 15L; });
    for (std::size_t i = 1; i < run.starts.size(); ++i) {
        EXPECT_GE(run.starts[i] - run.starts[i - 1], 15) << i;
        EXPECT_LE(run.starts[i] - run.starts[i - 1], 20) << i;
    }
    EXPECT_NEAR(static_cast<double>(run.skipped), 100.0, 2.0); // one grid point in three
    // Every grid point up to the last tick's was either run or dropped, once.
    EXPECT_EQ(run.skipped + run.starts.size(), static_cast<std::uint64_t>(run.last_due / 10));
}

} // namespace
} // namespace dsoc::server
