#include "dsoc/simclient/sample_histogram.hpp"

#include <gtest/gtest.h>

#include <random>

namespace dsoc::simclient {
namespace {

// Against the exact summary of the same samples (common::summarize): count, mean and
// max exact, percentiles within the stated 0.8%.
TEST(SampleHistogram, PercentilesWithinPrecisionOfTheExactOnes) {
    std::mt19937 rng(3);
    std::lognormal_distribution<double> latency(3.5, 0.6); // ms, like snapshot inter-arrival
    std::uniform_int_distribution<int> known(0, 900);      // entities known
    for (int kind = 0; kind < 2; ++kind) {
        SampleHistogram h;
        std::vector<double> samples;
        for (int i = 0; i < 50000; ++i) {
            const double v = kind == 0 ? latency(rng) : static_cast<double>(known(rng));
            samples.push_back(v);
            h.add(v);
        }
        const common::Summary exact = common::summarize(samples);
        const common::Summary got = h.summary();
        EXPECT_EQ(got.count, exact.count);
        EXPECT_NEAR(got.mean, exact.mean, 1e-9 * exact.mean);
        EXPECT_EQ(got.max, exact.max);
        for (const auto& [a, b] : {std::pair{got.p50, exact.p50}, std::pair{got.p95, exact.p95},
                                   std::pair{got.p99, exact.p99}}) {
            EXPECT_NEAR(a, b, 0.008 * b + 1e-9) << "kind " << kind;
        }
    }
}

TEST(SampleHistogram, MergeEqualsAddingEverythingToOne) {
    SampleHistogram a;
    SampleHistogram b;
    SampleHistogram all;
    for (int i = 0; i < 1000; ++i) {
        const double v = 0.37 * i;
        (i % 3 == 0 ? a : b).add(v);
        all.add(v);
    }
    a.merge(b);
    const auto m = a.summary();
    const auto s = all.summary();
    EXPECT_EQ(m.count, s.count);
    EXPECT_DOUBLE_EQ(m.mean, s.mean);
    EXPECT_EQ(m.p50, s.p50);
    EXPECT_EQ(m.p99, s.p99);
    EXPECT_EQ(m.max, s.max);
}

TEST(SampleHistogram, ZerosNegativesAndNonFiniteSamples) {
    SampleHistogram h;
    EXPECT_EQ(h.summary().count, 0u);
    h.add(0.0);
    h.add(-1.0);                                     // ignored
    h.add(std::numeric_limits<double>::quiet_NaN()); // ignored
    h.add(1e12);                                     // beyond the range: last bucket
    const auto s = h.summary();
    EXPECT_EQ(s.count, 2u);
    EXPECT_EQ(s.p50, 0.0);
    EXPECT_EQ(s.max, 1e12);
    EXPECT_EQ(s.p99, 1e12); // clamped to the exact maximum
}

} // namespace
} // namespace dsoc::simclient
