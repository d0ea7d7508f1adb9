#include "dsoc/simclient/delay_line.hpp"

#include <algorithm>

namespace dsoc::simclient {

DelayLine::DelayLine(boost::asio::io_context& io, double latency_ms, double jitter_ms,
                     std::uint64_t seed)
    : timer_(io), latency_ms_(latency_ms), jitter_ms_(jitter_ms), rng_(seed) {}

DelayLine::Clock::time_point DelayLine::push(std::function<void()> work,
                                             std::shared_ptr<void> keepalive,
                                             std::optional<Clock::time_point> arrived) {
    std::uniform_real_distribution<double> jitter(0.0, jitter_ms_);
    const double delay_ms = latency_ms_ + (jitter_ms_ > 0.0 ? jitter(rng_) : 0.0);
    const auto due =
        std::max(last_due_, arrived.value_or(Clock::now()) +
                                std::chrono::microseconds(static_cast<long>(delay_ms * 1000.0)));
    last_due_ = due;
    items_.push_back({due, std::move(work)});
    if (!armed_) {
        arm(std::move(keepalive));
    }
    return due;
}

void DelayLine::clear() {
    items_.clear(); // the armed timer finds nothing due and stops
}

void DelayLine::arm(std::shared_ptr<void> keepalive) {
    if (items_.empty()) {
        return;
    }
    armed_ = true;
    timer_.expires_at(items_.front().due);
    timer_.async_wait([this, keepalive](const boost::system::error_code& ec) {
        armed_ = false;
        if (ec) {
            return;
        }
        const auto now = Clock::now();
        while (!items_.empty() && items_.front().due <= now) {
            auto work = std::move(items_.front().work);
            items_.pop_front();
            work(); // may push more, or clear()
        }
        if (!armed_) {
            arm(keepalive);
        }
    });
}

} // namespace dsoc::simclient
