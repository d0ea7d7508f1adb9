#include "dsoc/simclient/load_run.hpp"

#include "dsoc/simclient/failure_reason.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <tuple>

namespace dsoc::simclient {

namespace asio = boost::asio;

namespace {
constexpr auto kControlPeriod = std::chrono::milliseconds(20);
/// Sessions that must all fail, none having connected, before the run gives up.
constexpr int kFailuresBeforeGivingUp = 3;
} // namespace

int shard_share(int total, Shard shard) {
    // The clients 0..total-1 dealt round the shards: shard i has those equal to i
    // modulo count, so the shards' clients are named by the stride below.
    return total > shard.index ? (total - shard.index + shard.count - 1) / shard.count : 0;
}

bool SharedRunState::first_failure_of(const std::string& reason) {
    const std::lock_guard lock(mutex_);
    return reasons_seen_.insert(reason).second;
}

std::vector<int> shard_group_shares(int total, const std::vector<ClientGroup>& groups,
                                    Shard shard) {
    std::vector<int> shares = split_by_weight(total, groups);
    for (std::size_t g = 0; g < shares.size(); ++g) {
        const int first = static_cast<int>(g % static_cast<std::size_t>(shard.count));
        const int dealt = (shard.index - first + shard.count) % shard.count;
        shares[g] = shard_share(shares[g], Shard{dealt, shard.count});
    }
    return shares;
}

LoadRun::LoadRun(asio::io_context& io, LoadConfig config, Shard shard,
                 std::shared_ptr<SharedRunState> shared)
    : io_(io), config_(std::move(config)), shard_(shard),
      shared_(shared ? std::move(shared) : std::make_shared<SharedRunState>()),
      scenario_(config_.scenario
                    ? *config_.scenario
                    : implicit_scenario(config_.clients, config_.duration_s, config_.ramp_up_s)),
      groups_(scenario_.groups.size()), control_timer_(io),
      rng_(config_.seed + static_cast<std::uint64_t>(shard.index)), next_index_(shard.index) {
    if (config_.connect_timeout_s) {
        scenario_.connect_timeout_s = *config_.connect_timeout_s;
    }
    scenario_.thresholds.insert(scenario_.thresholds.end(), config_.thresholds.begin(),
                                config_.thresholds.end());
}

void LoadRun::on_finished(std::function<void()> callback) {
    on_finished_ = std::move(callback);
}

void LoadRun::on_stopping(std::function<void(const std::string&)> callback) {
    on_stopping_ = std::move(callback);
}

double LoadRun::elapsed_s() const {
    return std::chrono::duration<double>(Clock::now() - started_).count();
}

void LoadRun::start() {
    started_ = Clock::now();
    last_control_ = started_;
    started_once_ = true;
    control();
}

void LoadRun::control() {
    if (stopping_) {
        return;
    }
    const auto now = Clock::now();
    const double t = std::chrono::duration<double>(now - started_).count();
    if (t >= scenario_.length_s()) {
        stop();
        return;
    }
    const double dt = std::chrono::duration<double>(now - last_control_).count();
    last_control_ = now;
    const std::vector<int> shares =
        shard_group_shares(target_at(scenario_.stages, t), scenario_.groups, shard_);
    target_ = 0;
    int connected = 0;
    for (std::size_t g = 0; g < groups_.size(); ++g) {
        target_ += shares[g];
        follow(g, shares[g], now, dt);
        for (const Slot& s : groups_[g].slots) {
            connected += s.client->connected() ? 1 : 0;
        }
    }
    peak_connected_ = std::max(peak_connected_, connected);
    if (connected > 0) {
        shared_->any_hello = true;
    }
    const int run_connected =
        shared_->connected.fetch_add(connected - connected_told_) + (connected - connected_told_);
    connected_told_ = connected;
    int peak = shared_->peak_connected.load();
    while (run_connected > peak &&
           !shared_->peak_connected.compare_exchange_weak(peak, run_connected)) {
    }
    control_timer_.expires_at(now + kControlPeriod);
    control_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec) {
            control();
        }
    });
}

void LoadRun::follow(std::size_t g, int share, Clock::time_point now, double dt_s) {
    GroupState& gs = groups_[g];
    const ClientGroup& group = scenario_.groups[g];
    // Respawners whose time has come leave, to come back as themselves once closed.
    if (group.behaviour == Behaviour::respawner) {
        for (Slot& s : gs.slots) {
            if (!s.respawning && s.client->connected() && now >= s.leave_at) {
                s.respawning = true;
                s.client->stop();
            }
        }
    }
    // Churn: a connected session leaves for good; a new client takes its place below.
    gs.churn_owed += group.churn_per_s * dt_s / shard_.count; // the shards share it
    while (gs.churn_owed >= 1.0) {
        std::vector<std::size_t> candidates;
        for (std::size_t i = 0; i < gs.slots.size(); ++i) {
            if (gs.slots[i].client->connected() && !gs.slots[i].respawning) {
                candidates.push_back(i);
            }
        }
        if (candidates.empty()) {
            gs.churn_owed = std::min(gs.churn_owed, 1.0);
            break;
        }
        gs.churn_owed -= 1.0;
        std::uniform_int_distribution<std::size_t> pick(0, candidates.size() - 1);
        const std::size_t i = candidates[pick(rng_)];
        gs.slots[i].client->stop();
        gs.slots.erase(gs.slots.begin() + static_cast<long>(i));
    }
    // Follow the share: the newest sessions leave first (as k6 ramps down).
    while (static_cast<int>(gs.slots.size()) > share) {
        gs.slots.back().client->stop();
        gs.slots.pop_back();
    }
    while (static_cast<int>(gs.slots.size()) < share) {
        int index = next_index_;
        if (!gs.respawning_indexes.empty()) {
            index = gs.respawning_indexes.back();
            gs.respawning_indexes.pop_back();
        } else {
            next_index_ += shard_.count;
        }
        start_session(g, index);
    }
}

bool picked_to_check(int index, std::uint32_t check_every) {
    if (check_every <= 1) {
        return true;
    }
    const auto i = static_cast<std::uint64_t>(index);
    std::uint64_t z = i / check_every + 0x9e3779b97f4a7c15ULL; // splitmix64 of the run
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return (z ^ (z >> 31)) % check_every == i % check_every;
}

namespace {

/// Between a session lost with its server and its replacement at the next one.
constexpr auto kFailoverPause = std::chrono::milliseconds(200);
} // namespace

std::pair<std::string, std::uint16_t> LoadRun::server_of(int index) const {
    const std::size_t count = 1 + config_.more_servers.size();
    const auto it = failovers_of_.find(index);
    const std::size_t k = (static_cast<std::size_t>(index) +
                           static_cast<std::size_t>(it == failovers_of_.end() ? 0 : it->second)) %
                          count;
    return k == 0 ? std::pair{config_.host, config_.port} : config_.more_servers[k - 1];
}

bool LoadRun::fails_over(const SimClient& client) const {
    const std::string& why = client.stats().failure;
    // A gateway whose world restarted, or that has no entity id for it yet, asks its
    // clients to connect again: with one server, to the same one.
    const bool asked_back = why == failure::world_restarted || why == failure::try_again;
    if (stopping_ || (config_.more_servers.empty() && !asked_back)) {
        return false;
    }
    // A client whose sessions failed before their hello at every server twice in a row:
    // no server is up, and that is a failure, not a failover.
    const auto it = unanswered_of_.find(client.setup().index);
    const std::size_t in_a_row = it == unanswered_of_.end() ? 0 : it->second;
    if (!client.stats().hello_received && in_a_row >= 2 * (1 + config_.more_servers.size())) {
        return false;
    }
    return why == failure::refused || why == failure::timeout || why == failure::connection_lost ||
           why == failure::connect_error || why == failure::server_shutdown || asked_back;
}

void LoadRun::start_session(std::size_t g, int index) {
    const std::shared_ptr<SimClient> client = start_client(g, index);
    Slot slot{client, Clock::now(), false};
    const ClientGroup& group = scenario_.groups[g];
    if (group.behaviour == Behaviour::respawner) {
        std::uniform_real_distribution<double> spread(0.5, 1.5);
        slot.leave_at += std::chrono::microseconds(
            static_cast<long>(group.respawn_every_s * spread(rng_) * 1e6));
    }
    groups_[g].slots.push_back(std::move(slot));
}

std::shared_ptr<SimClient> LoadRun::start_client(std::size_t g, int index) {
    SessionSetup setup;
    setup.group = &scenario_.groups[g];
    setup.index = index;
    GroupState& gs = groups_[g];
    if (gs.first_index < 0) {
        gs.first_index = index;
    }
    setup.checks_snapshots = index == gs.first_index || picked_to_check(index, config_.check_every);
    std::tie(setup.host, setup.port) = server_of(index);
    setup.session = clients_.size() * static_cast<std::size_t>(shard_.count) +
                    static_cast<std::size_t>(shard_.index);
    setup.connect_timeout_s = scenario_.connect_timeout_s;
    setup.run_end =
        started_ + std::chrono::microseconds(static_cast<long>(scenario_.length_s() * 1e6));
    setup.on_interarrival = [this](double ms) { second_interarrival_.add(ms); };
    setup.on_failure = [this](SimClient& c) { on_session_failure(c); };
    setup.on_closed = [this](SimClient& c) { on_session_closed(c); };
    auto client = std::make_shared<SimClient>(io_, config_, std::move(setup));
    clients_.push_back(client);
    client->start();
    return client;
}

void LoadRun::on_session_failure(SimClient& client) {
    const ClientStats& s = client.stats();
    if (fails_over(client)) {
        // Replaced by a session of the same client at the next server once it closed.
        client.mark_failed_over();
        failing_over_.insert(&client);
        const int index = client.setup().index;
        ++failovers_of_[index];
        std::size_t& in_a_row = unanswered_of_[index];
        in_a_row = s.hello_received ? 0 : in_a_row + 1;
        if (config_.progress) {
            const auto next = server_of(index);
            std::fprintf(stderr, "[%5.1fs] %s lost %s:%u (%s), reconnecting to %s:%u\n",
                         elapsed_s(), client.name().c_str(), client.setup().host.c_str(),
                         static_cast<unsigned>(client.setup().port), s.failure.c_str(),
                         next.first.c_str(), static_cast<unsigned>(next.second));
        }
        return;
    }
    ++failures_;
    const std::uint64_t run_failures = ++shared_->failures;
    ++failures_by_reason_[s.failure];
    ++second_failures_[s.failure];
    if (config_.progress && shared_->first_failure_of(s.failure)) {
        std::fprintf(stderr, "[%5.1fs] %s failed: %s: %s\n", elapsed_s(), client.name().c_str(),
                     s.failure.c_str(), s.failure_detail.c_str());
    }
    if (stopping_) {
        return;
    }
    if (s.failure == failure::server_shutdown) {
        stop(fmt::format("the server shut down at {:.1f} s, before the scenario's end at {:.1f} s",
                         elapsed_s(), scenario_.length_s()));
        return;
    }
    const int needed = std::min(kFailuresBeforeGivingUp, std::max(1, scenario_.peak_target()));
    for (const auto& c : clients_) {
        if (c->stats().hello_received) {
            shared_->any_hello = true;
        }
    }
    if (!shared_->any_hello && run_failures >= static_cast<std::uint64_t>(needed)) {
        stop(fmt::format("no client could connect ({})", join_counts(failures_by_reason_)));
    }
}

void LoadRun::on_session_closed(SimClient& client) {
    if (failing_over_.erase(&client) != 0 && !stopping_) {
        // The slot stays taken (the stages do not fill it with a new client) and gets a
        // session of the same client at the next server after a pause: not under the
        // closing session's own handler, and not in a tight loop while a server restarts.
        auto timer = std::make_shared<asio::steady_timer>(io_, kFailoverPause);
        timer->async_wait([this, lost = &client, timer](const boost::system::error_code& ec) {
            if (ec || stopping_) {
                maybe_finished();
                return;
            }
            for (std::size_t g = 0; g < groups_.size(); ++g) {
                for (Slot& slot : groups_[g].slots) {
                    if (slot.client.get() == lost) { // still there: the stages kept it
                        slot.client = start_client(g, lost->setup().index);
                        return;
                    }
                }
            }
        });
        return;
    }
    if (!stopping_) {
        for (GroupState& gs : groups_) {
            for (auto it = gs.slots.begin(); it != gs.slots.end(); ++it) {
                if (it->client.get() == &client && it->respawning) {
                    gs.respawning_indexes.push_back(client.setup().index);
                    gs.slots.erase(it);
                    return;
                }
            }
        }
    }
    maybe_finished();
}

void LoadRun::stop(const std::string& why) {
    if (stopping_) {
        return;
    }
    stopping_ = true;
    stopped_ = Clock::now();
    stopped_early_ = why;
    control_timer_.cancel();
    if (on_stopping_) {
        on_stopping_(stopped_early_);
    }
    if (started_once_) {
        last_second_ = count_second(); // before the sessions are told to stop
    }
    for (auto& c : clients_) {
        c->stop();
    }
    // Posted: a stop() from a session's hook must not finish the run under it.
    asio::post(io_, [this] { maybe_finished(); });
}

void LoadRun::maybe_finished() {
    if (!stopping_ || finished_) {
        return;
    }
    for (const auto& c : clients_) {
        if (!c->finished()) {
            return;
        }
    }
    finished_ = true;
    if (on_finished_) {
        on_finished_();
    }
}

ShardSecond LoadRun::take_shard_second() {
    return stopping_ ? ShardSecond{} : count_second();
}

ShardSecond LoadRun::take_last_second() {
    if (!last_second_) {
        return count_second();
    }
    ShardSecond last = std::move(*last_second_);
    last_second_.reset();
    return last;
}

ShardSecond LoadRun::count_second() {
    ShardSecond out;
    SecondSample& s = out.sample;
    s.target = target_;
    std::uint64_t down = 0;
    std::uint64_t up = 0;
    std::uint64_t snapshots = 0;
    for (const auto& c : clients_) {
        s.connected += c->connected() ? 1 : 0;
        s.connecting += c->connecting() ? 1 : 0;
        down += c->stats().bytes_down;
        up += c->stats().bytes_up;
        snapshots += c->stats().snapshots;
        for (const auto& [kind, n] : c->stats().protocol_errors) {
            s.protocol_errors_total += n;
        }
    }
    s.bytes_down = down - last_bytes_down_;
    s.bytes_up = up - last_bytes_up_;
    s.snapshots = snapshots - last_snapshots_;
    last_bytes_down_ = down;
    last_bytes_up_ = up;
    last_snapshots_ = snapshots;
    out.interarrival_ms = std::move(second_interarrival_);
    second_interarrival_ = SampleHistogram{};
    s.failures.swap(second_failures_);
    second_failures_.clear();
    s.failures_total = failures_;
    peak_connected_ = std::max(peak_connected_, s.connected);
    return out;
}

LoadReport LoadRun::report() const {
    LoadReport r = summarize_sessions(clients_);
    r.config = config_;
    r.scenario_seconds = scenario_.length_s();
    const auto end = stopping_ ? stopped_ : Clock::now();
    r.wall_seconds = std::chrono::duration<double>(end - started_).count();
    r.peak_connected = std::max(r.peak_connected, peak_connected_);
    r.stopped_early = stopped_early_;
    r.thresholds = evaluate_thresholds(scenario_.thresholds, r);
    return r;
}

} // namespace dsoc::simclient
