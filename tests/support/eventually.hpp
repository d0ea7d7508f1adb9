#pragma once
// Waiting for something another thread or process does: polls `done` until it holds.

#include <chrono>
#include <thread>

namespace dsoc::testing {

/// True once `done()` holds, polled every 2 ms; false after `timeout`.
template <typename F>
bool eventually(F done, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!done()) {
        if (std::chrono::steady_clock::now() > deadline) {
            return false;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return true;
}

} // namespace dsoc::testing
