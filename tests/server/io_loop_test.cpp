// IoLoop (dsoc/server/io_loop.hpp): the I/O thread's loop lets socket events gather,
// reads what arrived meanwhile in one wakeup, and wake() cuts a gather short.

#include "dsoc/server/io_loop.hpp"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

namespace dsoc::server {
namespace {

namespace asio = boost::asio;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

/// Posts a handler from another thread once the loop has run its first handler and
/// sleeps in a gather (if it gathers); returns how long after the post it ran.
milliseconds post_latency_during_gather(std::chrono::microseconds gather, bool wake) {
    asio::io_context io;
    IoLoop loop(io, gather);
    Clock::time_point posted;
    Clock::time_point ran;
    // Work that only another thread will bring: the loop, like io_context::run(),
    // would otherwise return once the first handler is done.
    auto work = asio::make_work_guard(io);
    asio::steady_timer first(io);
    first.expires_after(milliseconds(1));
    std::thread poster;
    first.async_wait([&](const boost::system::error_code&) {
        // The loop gathers as soon as this handler returns; post well inside that time.
        poster = std::thread([&] {
            std::this_thread::sleep_for(milliseconds(50));
            posted = Clock::now();
            asio::post(io, [&] {
                ran = Clock::now();
                work.reset();
            });
            if (wake) {
                loop.wake();
            }
        });
    });
    loop.run();
    poster.join();
    return std::chrono::duration_cast<milliseconds>(ran - posted);
}

TEST(IoLoop, AHandlerPostedFromAnotherThreadWaitsOutTheGatherUnlessWoken) {
    const auto gather = std::chrono::microseconds(600'000);
    EXPECT_GE(post_latency_during_gather(gather, false), milliseconds(400));
    EXPECT_LT(post_latency_during_gather(gather, true), milliseconds(300));
}

TEST(IoLoop, GatherZeroIsThePlainRun) {
    EXPECT_LT(post_latency_during_gather(std::chrono::microseconds(0), false), milliseconds(300));
    asio::io_context io;
    IoLoop loop(io, std::chrono::microseconds(0));
    int ran = 0;
    for (int i = 0; i < 3; ++i) {
        asio::post(io, [&] { ++ran; });
    }
    loop.run();
    EXPECT_EQ(ran, 3);
    EXPECT_EQ(loop.wakeups(), 0u); // io_context::run() itself counts nothing
}

/// Clients that write while the loop gathers are all read in the one wakeup that
/// follows the gather, where a loop that waited for each would wake once per client.
TEST(IoLoop, WhatArrivesDuringAGatherIsReadInOneWakeup) {
    constexpr int kClients = 20;
    asio::io_context io;
    IoLoop loop(io, std::chrono::microseconds(400'000));
    asio::ip::tcp::acceptor acceptor(io, {asio::ip::make_address("127.0.0.1"), 0});
    const auto endpoint = acceptor.local_endpoint();

    std::vector<std::unique_ptr<asio::ip::tcp::socket>> served;
    std::array<char, kClients> buffers{};
    int read = 0;
    std::uint64_t first_read_wakeup = 0; // loop.wakeups() as the first and last read ran
    std::uint64_t last_read_wakeup = 0;

    asio::io_context client_io;
    std::vector<asio::ip::tcp::socket> clients;
    for (int i = 0; i < kClients; ++i) {
        clients.emplace_back(client_io);
        clients.back().connect(endpoint);
        served.push_back(std::make_unique<asio::ip::tcp::socket>(acceptor.accept()));
    }
    for (int i = 0; i < kClients; ++i) {
        served[i]->async_read_some(asio::buffer(&buffers[i], 1),
                                   [&](const boost::system::error_code& ec, std::size_t) {
                                       ASSERT_FALSE(ec);
                                       last_read_wakeup = loop.wakeups();
                                       if (read++ == 0) {
                                           first_read_wakeup = last_read_wakeup;
                                       }
                                   });
    }
    // A first handler starts the loop's gather; the clients write during it.
    std::thread writer;
    asio::post(io, [&] {
        writer = std::thread([&] {
            std::this_thread::sleep_for(milliseconds(50));
            for (auto& c : clients) { // a millisecond apart: one wakeup each, ungathered
                const char byte = 'x';
                asio::write(c, asio::buffer(&byte, 1));
                std::this_thread::sleep_for(milliseconds(1));
            }
        });
    });
    loop.run();
    writer.join();
    ASSERT_EQ(read, kClients);
    // One wakeup for the post, then one for all the reads (two if a slow writer was
    // not done by the gather's end): never one per client.
    EXPECT_GE(loop.wakeups(), 2u);
    EXPECT_LE(last_read_wakeup - first_read_wakeup, 1u);
}

} // namespace
} // namespace dsoc::server
