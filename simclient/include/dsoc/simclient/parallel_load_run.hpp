#pragma once
// A load run spread over threads, as k6 spreads its virtual users over cores: each
// thread runs one shard (a LoadRun on its own io_context) with its share of every
// stage's target, and the shards' seconds and sessions are merged into one time series
// and one report. One thread is the single-threaded LoadRun on a thread of its own.
//
// Why: one thread decodes every client's snapshot in turn, so after each server tick
// the last client reads its snapshot a whole burst of decoding late, and a load that
// needs more than one core cannot be generated at all.
//
// Threading: the caller's io_context (`io`) takes the samples, prints the progress
// lines and runs the hooks; each shard's sessions run only on their shard's thread.
// The shards share nothing but a copy of the config each and the run's counters
// (SharedRunState: atomics, and the failure reasons already printed).
//
// A shard's exception ends the process (std::terminate), as an exception out of a
// single run's io_context::run() in dsoc-simclient's main did.
//
// The shards follow the scenario together: each takes its share of every group's
// clients (dealt round the shards) and of its churn; the run gives up when its first
// sessions all failed, whichever shards they were in (SharedRunState). The run ends
// when every shard has ended; a shard that stops early (the server shut down, no
// client could connect) stops the others at once, with its reason. Which client gets
// which inputs for a given --seed depends on the number of threads (a session's number
// seeds them: shard i numbers its sessions i, i + n, ...).

#include "dsoc/simclient/load_run.hpp"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace dsoc::simclient {

class ParallelLoadRun {
public:
    /// `threads` shards, at most one per client of the scenario's peak target.
    /// [Limit: threads >= 1] `config` as for LoadRun.
    ParallelLoadRun(boost::asio::io_context& io, LoadConfig config, int threads);
    /// Stops the shards and joins their threads if the run is not over.
    ~ParallelLoadRun();
    ParallelLoadRun(const ParallelLoadRun&) = delete;
    ParallelLoadRun& operator=(const ParallelLoadRun&) = delete;

    /// Called on `io` with every second's sample, merged over the shards (and the last,
    /// shorter one at the end).
    void on_second(std::function<void(const SecondSample&)> callback);
    /// Called once on `io`, when every shard is over and its thread joined.
    void on_finished(std::function<void()> callback);

    /// Starts the shards' threads; io_context::run() on `io` returns when the run is over.
    void start();
    /// Ends the run now (e.g. on SIGINT). `why`, when not empty, is reported as the
    /// reason the run stopped early. On `io`.
    void stop(const std::string& why = {});

    [[nodiscard]] int threads() const { return static_cast<int>(shards_.size()); }
    /// The whole run's report. Once finished (after on_finished).
    [[nodiscard]] LoadReport report() const;
    /// Every shard's sessions, by session number. Once finished.
    [[nodiscard]] std::vector<std::shared_ptr<SimClient>> clients() const;

private:
    using Clock = std::chrono::steady_clock;
    using WorkGuard = boost::asio::executor_work_guard<boost::asio::io_context::executor_type>;
    struct ShardRun {
        boost::asio::io_context io{1};
        std::optional<WorkGuard> guard; ///< keeps `io` running until the run is merged
        std::unique_ptr<LoadRun> run;
        std::thread thread;
        bool finished = false; ///< on `io_` (the caller's)
    };

    void sample_second();
    /// Every shard's counts (`take`: since the last call, or its last second), merged,
    /// as the second that ends at `end`. Blocks until each shard's thread has taken its
    /// own.
    [[nodiscard]] SecondSample take_sample(ShardSecond (LoadRun::*take)(), Clock::time_point end);
    void begin_stopping();
    void on_shard_stopping(const std::string& why);
    void on_shard_finished(ShardRun& shard);
    void finish();
    void join();

    boost::asio::io_context& io_;
    LoadConfig config_;
    std::shared_ptr<SharedRunState> shared_ = std::make_shared<SharedRunState>();
    std::vector<std::unique_ptr<ShardRun>> shards_;
    std::optional<WorkGuard> io_guard_;
    boost::asio::steady_timer second_timer_;
    std::function<void(const SecondSample&)> on_second_;
    std::function<void()> on_finished_;
    Clock::time_point started_;
    Clock::time_point stopped_;
    bool stopping_ = false;
    bool finished_ = false;
    std::string stopped_early_;
    double last_sample_s_ = 0.0;
};

} // namespace dsoc::simclient
