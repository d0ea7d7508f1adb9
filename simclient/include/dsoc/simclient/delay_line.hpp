#pragma once
// Emulated one-way latency on one direction of a TCP connection: work handed in runs
// `latency` (+ a uniform 0..jitter) later, in the order it was handed in (TCP never
// reorders, so neither does this). Used by SimClient for a group's network conditions.
//
// Threading: the io_context's thread only. Lifetime: each pending item keeps the
// `keepalive` it was pushed with (the SimClient) alive until it has run.

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <random>

namespace dsoc::simclient {

class DelayLine {
public:
    DelayLine(boost::asio::io_context& io, double latency_ms, double jitter_ms, std::uint64_t seed);

    /// Runs `work` the delay after `arrived` (when it reached this end; now by default),
    /// after everything pushed before it. Returns when it is due: where the emulated
    /// link delivers it.
    std::chrono::steady_clock::time_point
    push(std::function<void()> work, std::shared_ptr<void> keepalive,
         std::optional<std::chrono::steady_clock::time_point> arrived = std::nullopt);
    /// Drops what has not run yet.
    void clear();

private:
    using Clock = std::chrono::steady_clock;
    struct Item {
        Clock::time_point due;
        std::function<void()> work;
    };
    void arm(std::shared_ptr<void> keepalive);

    boost::asio::steady_timer timer_;
    double latency_ms_;
    double jitter_ms_;
    std::mt19937_64 rng_;
    std::deque<Item> items_;
    Clock::time_point last_due_{};
    bool armed_ = false;
};

} // namespace dsoc::simclient
