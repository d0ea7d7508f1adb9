#pragma once
// The I/O thread's loop: io_context::run(), except that after each wakeup that ran
// handlers the thread lets socket events gather for a while before it waits for them
// again, so that what arrives meanwhile (hundreds of clients' inputs, each sent at its
// own moment within the tick) is read in one wakeup instead of one each. Every input a
// client sends wakes a thread sleeping on the socket, and on a virtual machine each of
// those wakeups costs an interrupt between cores and a context switch, on the
// clients' side too; on this project's two-core machine 500 clients at 30 Hz caused
// about 15,000 a second. A gathered event waits at most `gather`: an input is applied
// at the next tick start anyway, and a ping's answer is late by less than that.
//
// What a gather must not delay is handed over with wake(): the server calls it when a
// tick's parallel phase ends (its hand-over is posted from a worker thread). Timers,
// the tick's included, fire up to `gather` late; a tick's start moves by that much,
// its duration and the tick rate do not.

#include <boost/asio/io_context.hpp>

#include <chrono>
#include <condition_variable>
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
