// Which simulated clients decode and check their snapshots (LoadConfig::check_every):
// exactly one in N, spread over every residue of the index, so that no server a client
// starts at (index modulo the servers) and no thread (index modulo the threads) is left
// with discarding clients only.

#include "dsoc/simclient/load_run.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace dsoc::simclient {
namespace {

TEST(CheckPicking, EveryClientChecksWhenNIsOne) {
    for (int i = 0; i < 100; ++i) {
        EXPECT_TRUE(picked_to_check(i, 1)) << i;
    }
}

TEST(CheckPicking, OneInEachRunOfNAndEveryResidueOfEveryModulusGetsCheckers) {
    for (const std::uint32_t n : {2u, 3u, 4u, 10u, 16u}) {
        const int clients = static_cast<int>(n * (2000 / n)); // whole runs of n
        int picked = 0;
        for (int run = 0; run * static_cast<int>(n) < clients; ++run) {
            int in_run = 0;
            for (int i = run * static_cast<int>(n); i < (run + 1) * static_cast<int>(n); ++i) {
                in_run += picked_to_check(i, n) ? 1 : 0;
            }
            EXPECT_EQ(in_run, 1) << "n " << n << ", run " << run;
            picked += in_run;
        }
        EXPECT_EQ(picked, clients / static_cast<int>(n));
        // Servers or threads: index modulo m, for m sharing a factor with n and not.
        for (const int m : {2, 3, 4, 5, 8, 10}) {
            std::vector<int> per_residue(static_cast<std::size_t>(m), 0);
            for (int i = 0; i < clients; ++i) {
                per_residue[static_cast<std::size_t>(i % m)] += picked_to_check(i, n) ? 1 : 0;
            }
            for (int r = 0; r < m; ++r) {
                EXPECT_GT(per_residue[static_cast<std::size_t>(r)], 0)
                    << "n " << n << ", residue " << r << " of " << m;
            }
        }
    }
}

} // namespace
} // namespace dsoc::simclient
