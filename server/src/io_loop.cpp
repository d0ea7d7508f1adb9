#include "dsoc/server/io_loop.hpp"

namespace dsoc::server {

IoLoop::IoLoop(boost::asio::io_context& io, std::chrono::microseconds gather)
    : io_(io), gather_(gather) {}

void IoLoop::run() {
    if (gather_.count() <= 0) {
        io_.run();
        return;
    }
    // run_one() sleeps until something is ready; poll() then runs all else that is;
    // while the thread gathers, nothing waits on the sockets, so arrivals wake nobody.
    while (io_.run_one() > 0) {
        ++wakeups_;
        // A wake() from before now is spent: its handler was posted before it, so
        // poll() runs it. (Left set, it would cut the next gather short for nothing.)
        {
            const std::lock_guard lock(mutex_);
            wake_ = false;
        }
        io_.poll();
        if (io_.stopped()) {
            return;
        }
        gather();
    }
}

void IoLoop::wake() {
    {
        const std::lock_guard lock(mutex_);
        wake_ = true;
    }
    woken_.notify_one();
}

void IoLoop::gather() {
    std::unique_lock lock(mutex_);
    woken_.wait_for(lock, gather_, [this] { return wake_; });
}

} // namespace dsoc::server
