#pragma once
// The I/O thread's loop: io_context::run(), except that after each wakeup that ran
// handlers the thread lets socket events gather for a while before it waits for them
// again, so that what arrives meanwhile (many clients' inputs, each sent at its own
// moment within the tick) is read in one wakeup instead of one each. A thread that
// sleeps on the sockets is woken for nearly every arrival, and each wakeup costs the
// sender an interrupt between cores (dear on a virtual machine) and the server a
// context switch.
//
// The contract, with `gather` the setting (ServerConfig::io_gather_us):
// - a socket event waits at most `gather` before its handler runs: an input reaches
//   the next tick start all the same, a ping's answer is late by at most `gather`;
// - timers fire up to `gather` late, the tick's too: a tick's start moves by that
//   much, its duration does not, and as long as `gather` is well below the tick
//   period (validate() allows a quarter) the tick rate does not;
// - a handler posted from another thread also waits out the gather unless the poster
//   calls wake() after posting: the server does so when a tick's parallel phase ends,
//   so that the hand-over starts at once.

#include <boost/asio/io_context.hpp>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace dsoc::server {

class IoLoop {
public:
    /// `gather` 0: io_context::run() itself.
    IoLoop(boost::asio::io_context& io, std::chrono::microseconds gather);

    /// Runs handlers until the io_context stops or runs out of work, on the calling
    /// thread (the I/O thread).
    void run();

    /// Ends the present gather at once (a handler was posted that must not wait), or
    /// the next one if none is under way. Any thread.
    void wake();

    /// How many times run() waited for events (a figure for tests).
    [[nodiscard]] std::uint64_t wakeups() const { return wakeups_; }

private:
    void gather();

    boost::asio::io_context& io_;
    std::chrono::microseconds gather_;
    std::mutex mutex_;
    std::condition_variable woken_;
    bool wake_ = false;
    std::uint64_t wakeups_ = 0;
};

} // namespace dsoc::server
