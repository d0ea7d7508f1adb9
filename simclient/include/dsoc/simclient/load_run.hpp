#pragma once
// A load run on one thread: sessions of simulated clients on one io_context, started
// and stopped to follow a scenario's stages, shared among its groups by weight (with
// their churn and respawns), stopped cleanly at the end, then summarized. Its owner
// (ParallelLoadRun, which runs one or more of them) takes its counts every second.
//
// The run ends at the scenario's end, or early: when the server shuts down before it
// (the run fails), when no session could connect (the first min(3, peak target)
// sessions all failed), or on stop(). A session that fails is not replaced: its place
// stays taken until the stages lower the count.
//
// A LoadRun may be one shard of several: it then follows its share of every group's
// target (shard_group_shares) and names its clients index, index + count, ..., so that
// the shards together are the whole scenario.

#include "dsoc/simclient/load_config.hpp"
#include "dsoc/simclient/load_report.hpp"
#include "dsoc/simclient/sample_histogram.hpp"
#include "dsoc/simclient/sim_client.hpp"
#include "dsoc/simclient/timeseries.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace dsoc::simclient {

/// Which part of a parallel run a LoadRun is: shard `index` of `count`.
struct Shard {
    int index = 0; ///< [Limit: 0..count-1]
    int count = 1; ///< [Limit: >= 1]
};

/// The shard's part of `total` clients: the clients 0..total-1 whose number is the
/// shard's index modulo the count. The parts of all shards sum to `total` and differ
/// by at most one.
[[nodiscard]] int shard_share(int total, Shard shard);

/// The shard's clients of each group when the run wants `total`: the run's total split
/// by weight (split_by_weight), then each group's clients dealt round the shards,
/// group g's first to shard g modulo the count (so that small groups spread out). Over
/// all shards, each group gets its split.
[[nodiscard]] std::vector<int> shard_group_shares(int total, const std::vector<ClientGroup>& groups,
                                                  Shard shard);

/// What the shards of one run share, so that the run's rules are the run's and not a
/// shard's: whether any session got its hello and how many failed (the run gives up
/// when its first sessions all failed), and how many are connected at once.
/// Thread-safe.
struct SharedRunState {
    std::atomic<bool> any_hello{false};
    std::atomic<std::uint64_t> failures{0};
    std::atomic<int> connected{0}; ///< the shards' counts at their last control step
    std::atomic<int> peak_connected{0};

    /// True the first time a session of the run fails for `reason` (its progress line
    /// is printed once per run, not once per shard).
    [[nodiscard]] bool first_failure_of(const std::string& reason);

private:
    std::mutex mutex_;
    std::set<std::string> reasons_seen_;
};

/// One shard's second, for its owner to merge with the others' (the interarrivals as a
/// histogram: percentiles do not add up).
struct ShardSecond {
    SecondSample sample; ///< t_s, interval_s and interarrival_ms not set
    SampleHistogram interarrival_ms;
};

/// Whether client `index` (>= 0) is one of the 1 in `check_every` that decode and check
/// (LoadConfig::check_every; 1: every client): one in each run of `check_every`
/// consecutive indexes, at a place a hash of the run picks, so that the checking clients
/// fall on every residue of the index (the server a client starts at, its thread) and
/// not only on those that share a factor with `check_every`.
[[nodiscard]] bool picked_to_check(int index, std::uint32_t check_every);

class LoadRun {
public:
    /// `config.scenario` (or the implicit one of its plain fields) must be valid
    /// (validate()).
    /// `shared`: the state of the whole run when this is one of its shards (nullptr:
    /// a run of its own).
    LoadRun(boost::asio::io_context& io, LoadConfig config, Shard shard = {},
            std::shared_ptr<SharedRunState> shared = nullptr);

    /// The counts since the last call (or the start), up to when the run started to
    /// stop (after that: nothing). On the run's io_context.
    [[nodiscard]] ShardSecond take_shard_second();
    /// Once the run has started to stop: the counts from the last take_shard_second()
    /// to that moment. On the run's io_context.
    [[nodiscard]] ShardSecond take_last_second();
    /// Why the run stopped before the scenario's end; "" when it did not.
    [[nodiscard]] const std::string& stopped_early() const { return stopped_early_; }

    /// Called once, when the run is over and every session has closed.
    void on_finished(std::function<void()> callback);
    /// Called once, when the run starts to stop (at the scenario's end, early, or on
    /// stop()), with the reason it stops early ("" at the scenario's end or a plain
    /// stop()).
    void on_stopping(std::function<void(const std::string& why)> callback);

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
        /// The group's first client here: it checks its snapshots whatever
        /// LoadConfig::check_every picks, so that no group goes unchecked.
        int first_index = -1;
    };

    void control();
    void follow(std::size_t group, int share, Clock::time_point now, double dt_s);
    /// A new slot of `group` with a session of client `index`.
    void start_session(std::size_t group, int index);
    /// A session of client `index` of `group`, started (for a slot of the caller's).
    std::shared_ptr<SimClient> start_client(std::size_t group, int index);
    void on_session_failure(SimClient& client);
    /// Whether `client`'s failure means its server is gone and the run has another to
    /// try (LoadConfig::more_servers), or its gateway asked it to connect again (its world
    /// restarted, or it had no entity id yet: then the same server will do when it is the
    /// only one).
    [[nodiscard]] bool fails_over(const SimClient& client) const;
    /// The server client `index` uses now: its first, moved on by its failovers.
    [[nodiscard]] std::pair<std::string, std::uint16_t> server_of(int index) const;
    void on_session_closed(SimClient& client);
    [[nodiscard]] ShardSecond count_second();
    void maybe_finished();
    [[nodiscard]] double elapsed_s() const;

    boost::asio::io_context& io_;
    LoadConfig config_;
    Shard shard_;
    std::shared_ptr<SharedRunState> shared_;
    Scenario scenario_;
    std::vector<GroupState> groups_;
    std::vector<std::shared_ptr<SimClient>> clients_;
    boost::asio::steady_timer control_timer_;
    std::function<void()> on_finished_;
    std::function<void(const std::string&)> on_stopping_;
    std::mt19937_64 rng_;
    Clock::time_point started_;
    Clock::time_point stopped_;
    Clock::time_point last_control_;
    bool started_once_ = false;
    bool stopping_ = false;
    bool finished_ = false;
    std::optional<ShardSecond> last_second_; ///< taken as the run starts to stop
    std::string stopped_early_;
    int next_index_ = 0;
    int target_ = 0;
    int peak_connected_ = 0;
    int connected_told_ = 0; ///< this shard's part of shared_->connected
    std::uint64_t failures_ = 0;
    std::map<int, int> failovers_of_;          ///< by client index: moves it to the next server
    std::map<int, std::size_t> unanswered_of_; ///< its failovers in a row before a hello
    std::set<const SimClient*> failing_over_;  ///< replaced once closed
    std::map<std::string, std::uint64_t> failures_by_reason_;
    // the current second
    std::uint64_t last_bytes_down_ = 0;
    std::uint64_t last_bytes_up_ = 0;
    std::uint64_t last_snapshots_ = 0;
    SampleHistogram second_interarrival_;
    std::map<std::string, std::uint64_t> second_failures_;
};

} // namespace dsoc::simclient
