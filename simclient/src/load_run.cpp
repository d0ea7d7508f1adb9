#include "dsoc/simclient/load_run.hpp"

#include <algorithm>
#include <cstdio>

namespace dsoc::simclient {

namespace asio = boost::asio;
using Clock = std::chrono::steady_clock;

LoadRun::LoadRun(asio::io_context& io, LoadConfig config)
    : io_(io), config_(std::move(config)), ramp_timer_(io), progress_timer_(io), end_timer_(io) {
    clients_.reserve(static_cast<std::size_t>(config_.clients));
    for (int i = 0; i < config_.clients; ++i) {
        clients_.push_back(std::make_shared<SimClient>(io_, config_, i));
    }
}

void LoadRun::start() {
    started_ = Clock::now();
    connect_next();
    end_timer_.expires_after(
        std::chrono::milliseconds(static_cast<long>(config_.duration_s * 1000)));
    end_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec) {
            stop();
        }
    });
    if (config_.progress) {
        progress_timer_.expires_after(std::chrono::seconds(1));
        progress_timer_.async_wait([this](const boost::system::error_code& ec) {
            if (!ec) {
                print_progress();
            }
        });
    }
}

void LoadRun::connect_next() {
    if (stopping_ || next_to_connect_ >= clients_.size()) {
        return;
    }
    clients_[next_to_connect_++]->start();
    if (next_to_connect_ >= clients_.size()) {
        return;
    }
    // Spread the connects evenly over the ramp-up.
    const double step_s = config_.ramp_up_s / static_cast<double>(clients_.size());
    const auto due = started_ + std::chrono::microseconds(static_cast<long>(
                                    step_s * 1e6 * static_cast<double>(next_to_connect_)));
    ramp_timer_.expires_at(due);
    ramp_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec) {
            connect_next();
        }
    });
}

void LoadRun::stop() {
    if (stopping_) {
        return;
    }
    stopping_ = true;
    stopped_ = Clock::now();
    ramp_timer_.cancel();
    progress_timer_.cancel();
    end_timer_.cancel();
    for (auto& c : clients_) {
        c->stop();
    }
}

void LoadRun::print_progress() {
    int connected = 0;
    std::uint64_t down = 0;
    std::uint64_t up = 0;
    std::uint64_t snapshots = 0;
    std::uint64_t errors = 0;
    for (const auto& c : clients_) {
        connected += c->connected() ? 1 : 0;
        down += c->stats().bytes_down;
        up += c->stats().bytes_up;
        snapshots += c->stats().snapshots;
        for (const auto& [kind, n] : c->stats().protocol_errors) {
            errors += n;
        }
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - started_).count();
    std::fprintf(stderr,
                 "[%5.1fs] clients %d/%d connected | snapshots/s %llu | down %.1f KiB/s | up "
                 "%.1f KiB/s | protocol errors %llu\n",
                 elapsed, connected, config_.clients,
                 static_cast<unsigned long long>(snapshots - last_snapshots_),
                 static_cast<double>(down - last_bytes_down_) / 1024.0,
                 static_cast<double>(up - last_bytes_up_) / 1024.0,
                 static_cast<unsigned long long>(errors));
    last_bytes_down_ = down;
    last_bytes_up_ = up;
    last_snapshots_ = snapshots;
    progress_timer_.expires_after(std::chrono::seconds(1));
    progress_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec && !stopping_) {
            print_progress();
        }
    });
}

LoadReport LoadRun::report() const {
    LoadReport r;
    r.config = config_;
    r.clients = config_.clients;
    const auto end = stopping_ ? stopped_ : Clock::now();
    r.wall_seconds = std::chrono::duration<double>(end - started_).count();
    SampleHistogram known;
    SampleHistogram interarrival;
    SampleHistogram rtt;
    double down_rate_sum = 0.0;
    double up_rate_sum = 0.0;
    double update_rate_sum = 0.0;
    for (const auto& c : clients_) {
        const ClientStats& s = c->stats();
        if (!s.hello_received) {
            ++r.connect_failures;
        } else {
            ++r.connected;
            if (!s.saw_own_entity) {
                ++r.missing_own_entity;
            }
            if (s.active_seconds > 0.0) {
                down_rate_sum += static_cast<double>(s.bytes_down) / s.active_seconds;
                up_rate_sum += static_cast<double>(s.bytes_up) / s.active_seconds;
                update_rate_sum += static_cast<double>(s.entity_updates) / s.active_seconds;
            }
        }
        r.unexpected_disconnects += s.unexpected_disconnect ? 1 : 0;
        if (!s.disconnect_reason.empty()) {
            ++r.disconnect_reasons[s.disconnect_reason];
        }
        for (const auto& [kind, n] : s.protocol_errors) {
            r.protocol_errors += n;
            r.protocol_errors_by_kind[kind] += n;
        }
        r.bytes_down += s.bytes_down;
        r.bytes_up += s.bytes_up;
        r.snapshots += s.snapshots;
        r.entity_updates += s.entity_updates;
        r.audited_poses += s.audited_poses;
        r.max_audit_error = std::max(r.max_audit_error, s.max_audit_error);
        known.merge(s.known_samples);
        interarrival.merge(s.interarrival_ms);
        rtt.merge(s.rtt_ms);
    }
    if (r.connected > 0) {
        r.bytes_down_per_client_s = down_rate_sum / r.connected;
        r.bytes_up_per_client_s = up_rate_sum / r.connected;
        r.entity_updates_per_client_s = update_rate_sum / r.connected;
    }
    r.entities_known = known.summary();
    r.snapshot_interarrival_ms = interarrival.summary();
    r.rtt_ms = rtt.summary();
    return r;
}

} // namespace dsoc::simclient
