// A load run over several threads: the shards' shares of the target, and a run that
// stops early on one shard ends on all of them.

#include "dsoc/simclient/parallel_load_run.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <gtest/gtest.h>

#include <algorithm>

namespace dsoc::simclient {
namespace {

TEST(ShardShare, TheSharesSumToTheTotalAndDifferByAtMostOne) {
    for (int count = 1; count <= 9; ++count) {
        for (int total = 0; total <= 1000; total += 7) {
            int sum = 0;
            int least = total;
            int most = 0;
            for (int i = 0; i < count; ++i) {
                const int share = shard_share(total, Shard{i, count});
                sum += share;
                least = std::min(least, share);
                most = std::max(most, share);
            }
            EXPECT_EQ(sum, total) << total << " over " << count;
            EXPECT_LE(most - least, 1) << total << " over " << count;
        }
    }
    // A ramp's first client starts at once in one of the shards.
    EXPECT_EQ(shard_share(1, Shard{0, 2}) + shard_share(1, Shard{1, 2}), 1);
    EXPECT_EQ(shard_share(1, Shard{0, 2}), 1);
    EXPECT_EQ(shard_share(10, Shard{0, 3}), 4); // clients 0, 3, 6, 9
    EXPECT_EQ(shard_share(10, Shard{2, 3}), 3); // clients 2, 5, 8
}

TEST(ShardGroupShares, EveryGroupGetsItsSplitOverTheShards) {
    std::vector<ClientGroup> three(3);
    three[0].weight = 2.0;
    three[1].weight = 1.0;
    three[2].weight = 1.0;
    std::vector<ClientGroup> two(2);
    two[0].weight = 3.0;
    two[1].weight = 1.0;
    for (const auto* groups : {&three, &two}) {
        for (int count = 1; count <= 8; ++count) {
            for (int total = 0; total <= 120; ++total) {
                const std::vector<int> whole = split_by_weight(total, *groups);
                std::vector<int> summed(groups->size(), 0);
                for (int i = 0; i < count; ++i) {
                    const std::vector<int> part =
                        shard_group_shares(total, *groups, Shard{i, count});
                    for (std::size_t g = 0; g < part.size(); ++g) {
                        summed[g] += part[g];
                    }
                }
                EXPECT_EQ(summed, whole) << total << " over " << count;
            }
        }
    }
    // Weights 3:1, 8 clients, 8 threads: the small group's two clients still run.
    int small = 0;
    for (int i = 0; i < 8; ++i) {
        small += shard_group_shares(8, two, Shard{i, 8})[1];
    }
    EXPECT_EQ(small, 2);
}

TEST(ParallelLoadRun, NoSessionCanConnectSoTheRunStopsEarlyOnEveryThread) {
    boost::asio::io_context io;
    std::uint16_t closed_port = 0;
    {
        // A port that was just free: nothing listens there.
        boost::asio::ip::tcp::acceptor probe(io, {boost::asio::ip::tcp::v4(), 0});
        closed_port = probe.local_endpoint().port();
    }
    LoadConfig config;
    config.transport = LoadConfig::Transport::tcp; // the port was a TCP listener's
    config.port = closed_port;
    config.clients = 12;
    config.duration_s = 30.0; // far longer than the test: the run must end early
    config.ramp_up_s = 0.0;
    config.progress = false;
    ParallelLoadRun run(io, config, 2);
    ASSERT_EQ(run.threads(), 2);
    bool finished = false;
    run.on_finished([&] { finished = true; });
    const auto before = std::chrono::steady_clock::now();
    run.start();
    io.run();
    const double took =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();

    EXPECT_TRUE(finished);
    EXPECT_LT(took, 10.0);
    const LoadReport report = run.report();
    EXPECT_FALSE(report.passed());
    EXPECT_NE(report.stopped_early.find("no client could connect"), std::string::npos)
        << report.stopped_early;
    EXPECT_EQ(report.connected, 0);
    // The run's first three sessions failed, whichever threads they ran in; those that
    // had not failed yet were cancelled.
    EXPECT_GE(report.failures, 3u);
    // Both shards' sessions are in the report, every one of them over.
    ASSERT_EQ(run.clients().size(), static_cast<std::size_t>(report.clients));
    for (const auto& client : run.clients()) {
        EXPECT_TRUE(client->finished());
    }
}

TEST(ParallelLoadRun, NeverMoreThreadsThanClients) {
    boost::asio::io_context io;
    LoadConfig config;
    config.clients = 3;
    config.progress = false;
    const ParallelLoadRun run(io, config, 8);
    EXPECT_EQ(run.threads(), 3);
}

} // namespace
} // namespace dsoc::simclient
