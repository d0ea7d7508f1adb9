// The allocator's figures (heap_stats.hpp) in a program linked as dsoc-server is: on
// jemalloc where the build found it, read without cost, and with freed pages given back
// to the system by jemalloc's background threads (server/src/jemalloc_options.cpp).
#include "dsoc/server/heap_stats.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace dsoc::server {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

TEST(HeapStats, RunsOnTheAllocatorDsocServerLinks) {
    EXPECT_EQ(std::string(allocator_name(running_heap_allocator())), DSOC_SERVER_ALLOCATOR);
}

TEST(HeapStats, LiveBytesFollowAnAllocationAndItsRelease) {
    if (running_heap_allocator() == HeapAllocator::unknown) {
        GTEST_SKIP() << "no allocator figures to read (" << DSOC_SERVER_ALLOCATOR << ")";
    }
    const auto before = read_heap_sample(true);
    ASSERT_TRUE(before.has_value());
    auto block = std::make_unique<std::vector<std::uint8_t>>(std::size_t{8} << 20, 1);
    const auto holding = read_heap_sample(true);
    block.reset();
    const auto released = read_heap_sample(true);
    ASSERT_TRUE(holding && released);
    EXPECT_GE(holding->in_use_bytes - before->in_use_bytes, 8 * kMiB);
    EXPECT_LE(released->in_use_bytes, holding->in_use_bytes - 8 * kMiB);
    EXPECT_GE(released->free_bytes, 0.0);
}

TEST(HeapStats, ReadOnlyWhenAskedWhereReadingMakesThreadsWait) {
    const HeapAllocator allocator = running_heap_allocator();
    EXPECT_EQ(read_heap_sample(false).has_value(), !heap_reading_is_costly(allocator));
}

// What the server runs on jemalloc for: memory freed after a burst (many small blocks,
// as a tick's frames and snapshots are) leaves the process within seconds, with no
// call of the program's own.
TEST(HeapStats, FreedPagesLeaveTheProcessOnJemalloc) {
    if (running_heap_allocator() != HeapAllocator::jemalloc) {
        GTEST_SKIP() << "built without jemalloc (" << DSOC_SERVER_ALLOCATOR << ")";
    }
    constexpr std::size_t kBlocks = 64 * 1024;
    constexpr std::size_t kBlockBytes = 1024; // 64 MiB in all
    std::vector<std::unique_ptr<std::uint8_t[]>> blocks;
    blocks.reserve(kBlocks);
    for (std::size_t i = 0; i < kBlocks; ++i) {
        blocks.push_back(std::make_unique<std::uint8_t[]>(kBlockBytes)); // zeroed: touched
    }
    blocks.clear();
    const auto freed = read_heap_sample(false);
    ASSERT_TRUE(freed.has_value());
    // Held at first: most of the 64 MiB (jemalloc may have begun to purge while the
    // blocks were being freed on a loaded machine: 44.7 MiB were left once in a parallel
    // ctest run), and well above what must remain below.
    ASSERT_GE(freed->free_bytes, 32 * kMiB) << "the freed blocks are held at first";
    // jemalloc purges them gradually over dirty_decay_ms (10 s): wait for most of them.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    double held = freed->free_bytes;
    while (held > 24 * kMiB && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        held = read_heap_sample(false)->free_bytes;
    }
    EXPECT_LE(held, 24 * kMiB) << "MiB still held after 30 s: " << held / kMiB;
}

} // namespace
} // namespace dsoc::server
