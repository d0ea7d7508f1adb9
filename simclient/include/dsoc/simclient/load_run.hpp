#pragma once
// A load run: sessions of simulated clients on one io_context, started and stopped to
// follow a scenario's stages, shared among its groups by weight (with their churn and
// respawns), sampled every second, stopped cleanly at the end, then summarized.
//
// The run ends at the scenario's end, or early: when the server shuts down before it
// (the run fails), when no session could connect (the first min(3, peak target)
// sessions all failed), or on stop(). A session that fails is not replaced: its place
// stays taken until the stages lower the count.

#include "dsoc/simclient/load_config.hpp"
#include "dsoc/simclient/load_report.hpp"
#include "dsoc/simclient/sim_client.hpp"
#include "dsoc/simclient/timeseries.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <functional>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace dsoc::simclient {

class LoadRun {
public:
    /// `config.scenario` (or the implicit one of its plain fields) must be valid
    /// (validate()).
    LoadRun(boost::asio::io_context& io, LoadConfig config);

    /// Called with every second's sample (and the last, shorter one at the end).
    void on_second(std::function<void(const SecondSample&)> callback);
    /// Called once, when the run is over and every session has closed.
    void on_finished(std::function<void()> callback);

    /// Schedules everything; io_context::run() returns when the run is over.
    void start();
    /// Ends the run now (e.g. on SIGINT): stops every session. `why`, when not empty,
    /// is reported as the reason the run stopped early.
    void stop(const std::string& why = {});

    [[nodiscard]] LoadReport report() const;
    /// Every session of the run, in the order they started.
    [[nodiscard]] const std::vector<std::shared_ptr<SimClient>>& clients() const {
        return clients_;
    }
    [[nodiscard]] const Scenario& scenario() const { return scenario_; }

private:
    using Clock = std::chrono::steady_clock;
    /// A place in a group: a session, and when a respawner leaves.
    struct Slot {
        std::shared_ptr<SimClient> client;
        Clock::time_point leave_at;
        bool respawning = false; ///< left to come back as itself once closed
    };
    struct GroupState {
        std::vector<Slot> slots;             ///< oldest first
        std::vector<int> respawning_indexes; ///< closed respawners, to reconnect
        double churn_owed = 0.0;             ///< sessions due to churn
    };

    void control();
    void follow(std::size_t group, int share, Clock::time_point now, double dt_s);
    void start_session(std::size_t group, int index);
    void on_session_failure(SimClient& client);
    void on_session_closed(SimClient& client);
    void sample_second();
    [[nodiscard]] SecondSample take_sample();
    void maybe_finished();
    [[nodiscard]] double elapsed_s() const;

    boost::asio::io_context& io_;
    LoadConfig config_;
    Scenario scenario_;
    std::vector<GroupState> groups_;
    std::vector<std::shared_ptr<SimClient>> clients_;
    boost::asio::steady_timer control_timer_;
    boost::asio::steady_timer second_timer_;
    std::function<void(const SecondSample&)> on_second_;
    std::function<void()> on_finished_;
    std::mt19937_64 rng_;
    Clock::time_point started_;
    Clock::time_point stopped_;
    Clock::time_point last_control_;
    bool started_once_ = false;
    bool stopping_ = false;
    bool finished_ = false;
    std::string stopped_early_;
    int next_index_ = 0;
    int target_ = 0;
    int peak_connected_ = 0;
    int ever_connected_ = 0;
    std::uint64_t failures_ = 0;
    std::map<std::string, std::uint64_t> failures_by_reason_;
    // the current second
    double last_sample_s_ = 0.0;
    std::uint64_t last_bytes_down_ = 0;
    std::uint64_t last_bytes_up_ = 0;
    std::uint64_t last_snapshots_ = 0;
    SampleHistogram second_interarrival_;
    std::map<std::string, std::uint64_t> second_failures_;
};

} // namespace dsoc::simclient
