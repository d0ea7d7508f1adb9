#include "dsoc/simclient/parallel_load_run.hpp"

#include <boost/asio/post.hpp>

#include <algorithm>
#include <cassert>
#include <cstdio>
#include <future>

namespace dsoc::simclient {

namespace asio = boost::asio;

ParallelLoadRun::ParallelLoadRun(asio::io_context& io, LoadConfig config, int threads)
    : io_(io), config_(std::move(config)), second_timer_(io) {
    const Scenario scenario =
        config_.scenario
            ? *config_.scenario
            : implicit_scenario(config_.clients, config_.duration_s, config_.ramp_up_s);
    const int count = std::clamp(threads, 1, std::max(1, scenario.peak_target()));
    for (int i = 0; i < count; ++i) {
        auto shard = std::make_unique<ShardRun>();
        shard->run = std::make_unique<LoadRun>(shard->io, config_, Shard{i, count}, shared_);
        ShardRun* raw = shard.get();
        shard->run->on_stopping([this](const std::string& why) {
            asio::post(io_, [this, why] { on_shard_stopping(why); });
        });
        shard->run->on_finished(
            [this, raw] { asio::post(io_, [this, raw] { on_shard_finished(*raw); }); });
        shards_.push_back(std::move(shard));
    }
}

ParallelLoadRun::~ParallelLoadRun() {
    if (finished_) {
        return;
    }
    for (auto& shard : shards_) {
        asio::post(shard->io, [run = shard->run.get()] { run->stop(); });
        shard->guard.reset();
    }
    join();
}

void ParallelLoadRun::on_second(std::function<void(const SecondSample&)> callback) {
    on_second_ = std::move(callback);
}

void ParallelLoadRun::on_finished(std::function<void()> callback) {
    on_finished_ = std::move(callback);
}

void ParallelLoadRun::start() {
    started_ = Clock::now();
    io_guard_.emplace(io_.get_executor());
    for (auto& shard : shards_) {
        shard->guard.emplace(shard->io.get_executor());
        asio::post(shard->io, [run = shard->run.get()] { run->start(); });
        shard->thread = std::thread([io = &shard->io] { io->run(); });
    }
    second_timer_.expires_at(started_ + std::chrono::seconds(1));
    second_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec && !stopping_) {
            sample_second();
        }
    });
}

void ParallelLoadRun::stop(const std::string& why) {
    if (stopping_ || finished_) {
        return;
    }
    begin_stopping();
    if (!why.empty()) {
        stopped_early_ = why;
        if (config_.progress) {
            const double t = std::chrono::duration<double>(stopped_ - started_).count();
            std::fprintf(stderr, "[%5.1fs] stopping early: %s\n", t, why.c_str());
        }
    }
    for (auto& shard : shards_) {
        asio::post(shard->io, [run = shard->run.get()] { run->stop(); });
    }
}

void ParallelLoadRun::on_shard_stopping(const std::string& why) {
    // The first shard to stop stops the run: at the scenario's end (the others stop on
    // their own within a control period) or early, which the others must follow.
    if (stopping_) {
        return;
    }
    if (why.empty()) {
        begin_stopping();
        return;
    }
    stop(why);
}

void ParallelLoadRun::begin_stopping() {
    stopping_ = true;
    stopped_ = Clock::now();
    second_timer_.cancel(); // the shards keep their last second for finish()
}

void ParallelLoadRun::on_shard_finished(ShardRun& shard) {
    shard.finished = true;
    if (std::all_of(shards_.begin(), shards_.end(), [](const auto& s) { return s->finished; })) {
        finish();
    }
}

void ParallelLoadRun::finish() {
    second_timer_.cancel();
    // The shards' last counts end where they started to stop.
    const SecondSample last = take_sample(&LoadRun::take_last_second, stopped_);
    if (last.interval_s > 0.05 && on_second_) {
        on_second_(last);
    }
    for (auto& shard : shards_) {
        shard->guard.reset();
    }
    join();
    finished_ = true;
    io_guard_.reset();
    if (on_finished_) {
        on_finished_();
    }
}

void ParallelLoadRun::join() {
    for (auto& shard : shards_) {
        if (shard->thread.joinable()) {
            shard->thread.join();
        }
    }
}

SecondSample ParallelLoadRun::take_sample(ShardSecond (LoadRun::*take)(), Clock::time_point end) {
    if (finished_) {
        return {}; // the shards' threads are gone: nothing would answer
    }
    std::vector<std::future<ShardSecond>> parts;
    for (auto& shard : shards_) {
        auto promise = std::make_shared<std::promise<ShardSecond>>();
        parts.push_back(promise->get_future());
        asio::post(shard->io,
                   [promise, take, run = shard->run.get()] { promise->set_value((run->*take)()); });
    }
    SecondSample s;
    s.t_s = std::chrono::duration<double>(end - started_).count();
    s.interval_s = s.t_s - last_sample_s_;
    last_sample_s_ = s.t_s;
    SampleHistogram interarrival;
    for (auto& part : parts) {
        const ShardSecond p = part.get();
        s.target += p.sample.target;
        s.connected += p.sample.connected;
        s.connecting += p.sample.connecting;
        s.snapshots += p.sample.snapshots;
        s.bytes_down += p.sample.bytes_down;
        s.bytes_up += p.sample.bytes_up;
        for (const auto& [reason, n] : p.sample.failures) {
            s.failures[reason] += n;
        }
        s.failures_total += p.sample.failures_total;
        s.protocol_errors_total += p.sample.protocol_errors_total;
        interarrival.merge(p.interarrival_ms);
    }
    s.interarrival_ms = interarrival.summary();
    return s;
}

void ParallelLoadRun::sample_second() {
    const SecondSample s = take_sample(&LoadRun::take_shard_second, Clock::now());
    if (config_.progress) {
        std::fprintf(stderr, "%s\n", format_progress_line(s).c_str());
    }
    if (on_second_) {
        on_second_(s);
    }
    second_timer_.expires_at(second_timer_.expiry() + std::chrono::seconds(1));
    second_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec && !stopping_) {
            sample_second();
        }
    });
}

std::vector<std::shared_ptr<SimClient>> ParallelLoadRun::clients() const {
    assert(finished_ && "clients() once the run is over: the shards' threads own the sessions");
    std::vector<std::shared_ptr<SimClient>> all;
    for (const auto& shard : shards_) {
        const auto& c = shard->run->clients();
        all.insert(all.end(), c.begin(), c.end());
    }
    std::sort(all.begin(), all.end(),
              [](const auto& a, const auto& b) { return a->setup().session < b->setup().session; });
    return all;
}

LoadReport ParallelLoadRun::report() const {
    assert(finished_ && "report() once the run is over: the shards' threads own the sessions");
    const Scenario& scenario = shards_.front()->run->scenario();
    LoadReport r = summarize_sessions(clients());
    r.config = config_;
    r.scenario_seconds = scenario.length_s();
    const auto end = (stopping_ || finished_) ? stopped_ : Clock::now();
    r.wall_seconds = std::chrono::duration<double>(end - started_).count();
    r.peak_connected = std::max(r.peak_connected, shared_->peak_connected.load());
    r.stopped_early = stopped_early_;
    r.thresholds = evaluate_thresholds(scenario.thresholds, r);
    return r;
}

} // namespace dsoc::simclient
