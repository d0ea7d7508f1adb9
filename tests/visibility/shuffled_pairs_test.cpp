#include "dsoc/visibility/shuffled_pairs.hpp"

#include <gtest/gtest.h>

#include <set>
#include <utility>

namespace dsoc::visibility {
namespace {

TEST(ShuffledPairs, EveryUnorderedPairOnceAndNoOther) {
    for (const std::uint64_t n : {0u, 1u, 2u, 3u, 7u, 64u, 65u, 300u}) {
        const ShuffledPairs pairs(n);
        ASSERT_EQ(pairs.count(), n * (n + 1) / 2);
        std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
        for (std::uint64_t k = 0; k < pairs.count(); ++k) {
            const auto [i, j] = pairs.at(k);
            ASSERT_LE(i, j) << "n " << n << " k " << k;
            ASSERT_LT(j, n) << "n " << n << " k " << k;
            ASSERT_TRUE(seen.insert({i, j}).second)
                << "n " << n << ": {" << i << ", " << j << "} twice";
        }
        ASSERT_EQ(seen.size(), pairs.count());
    }
}

TEST(ShuffledPairs, TheOrderIsScatteredNotRowByRow) {
    // The first tenth of the order must reach most rows: a row-by-row order would put
    // only the first few rows' pairs there (the costly pairs of a map's dense part
    // would then all come together, and the ETA would lie).
    const std::uint64_t n = 400;
    const ShuffledPairs pairs(n);
    std::set<std::uint32_t> rows;
    for (std::uint64_t k = 0; k < pairs.count() / 10; ++k) {
        rows.insert(pairs.at(k).first);
    }
    EXPECT_GT(rows.size(), n * 3 / 4);
}

TEST(ShuffledPairs, LargeCountsNeedNoList) {
    // 100,000 items: 5·10⁹ pairs. Spot checks of the index arithmetic at the ends.
    const ShuffledPairs pairs(100000);
    EXPECT_EQ(pairs.count(), 5000050000u);
    for (const std::uint64_t k :
         {std::uint64_t{0}, std::uint64_t{1}, pairs.count() / 2, pairs.count() - 1}) {
        const auto [i, j] = pairs.at(k);
        EXPECT_LE(i, j);
        EXPECT_LT(j, 100000u);
    }
}

} // namespace
} // namespace dsoc::visibility
