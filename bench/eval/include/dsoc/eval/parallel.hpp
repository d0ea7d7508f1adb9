#pragma once
// A minimal fork-join loop for the evaluation: indexes 0..count-1 handed out one at a
// time (an atomic counter) to `threads` threads, the caller being one of them.
// Threads are started per call: a tick's work is milliseconds, a thread start tens of
// microseconds.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace dsoc::eval {

/// Calls body(index, worker) for every index in [0, count); worker is in [0, threads).
/// Returns when all calls have returned. `body` must be safe to run concurrently for
/// distinct indexes.
template <class Body>
void parallel_for(std::size_t count, int threads, Body&& body) {
    const int n = std::max(1, std::min<int>(threads, static_cast<int>(count)));
    std::atomic<std::size_t> next{0};
    auto work = [&](int worker) {
        for (std::size_t i = next.fetch_add(1); i < count; i = next.fetch_add(1)) {
            body(i, worker);
        }
    };
    std::vector<std::thread> helpers;
    helpers.reserve(static_cast<std::size_t>(n - 1));
    for (int w = 1; w < n; ++w) {
        helpers.emplace_back(work, w);
    }
    work(0);
    for (auto& t : helpers) {
        t.join();
    }
}

} // namespace dsoc::eval
