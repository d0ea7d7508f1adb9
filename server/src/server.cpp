#include "dsoc/server/server.hpp"

#include "dsoc/server/datagram_batch.hpp"

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "dsoc/server/client_ids.hpp"
#include "dsoc/server/interest_setup.hpp"

#include <boost/asio/post.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <glm/common.hpp>

#include <algorithm>

namespace dsoc::server {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using Clock = std::chrono::steady_clock;

namespace {
/// Samples of tick cost kept for percentiles (a rolling window would do for a
/// long-running server; a day at 30 Hz is 2.6 M doubles, 20 MiB).
constexpr std::size_t kMaxTickSamples = 4'000'000;
} // namespace

Server::Server(asio::io_context& io, ServerConfig config, std::shared_ptr<const maps::Map> map)
    : io_(io), config_(std::move(config)), acceptor_(io), tick_timer_(io),
      tick_period_(std::chrono::nanoseconds(1'000'000'000LL / config_.tick_rate)),
      schedule_(Clock::now(), tick_period_), world_(world_settings(config_), std::move(map)),
      policy_(make_policy(config_, world_)), pool_(config_.threads, WorkerPool::Caller::stays_out) {
}

Server::~Server() {
    // The jobs of a phase in flight point into this server's members.
    pool_.wait_idle();
}

std::uint16_t Server::start() {
    const asio::ip::tcp::endpoint endpoint(asio::ip::make_address(config_.bind_address),
                                           config_.port);
    if (!config_.insecure) {
        token_key_ = std::make_unique<protocol::TokenKey>();
        std::string error;
        if (!protocol::load_token_key(config_.token_key_file, *token_key_, error)) {
            throw std::runtime_error(error);
        }
    } else {
        spdlog::warn("insecure: clients connect without a connect token");
    }
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(asio::socket_base::reuse_address(true));
    acceptor_.bind(endpoint);
    acceptor_.listen();
    const std::uint16_t port = acceptor_.local_endpoint().port();
    if (config_.udp) {
        udp_ = std::make_unique<UdpEndpoint>(
            io_, config_, static_cast<ConnectionHost&>(*this), [this] { return take_client_id(); },
            [this](const std::shared_ptr<Connection>& connection) { open_connection(connection); });
        udp_->start(config_.bind_address, port);
    }
    spdlog::info("dsoc-server listening on {}:{} ({}) map={} policy={} tick_rate={} Hz bots={} "
                 "threads={}",
                 config_.bind_address, port, config_.udp ? "tcp and udp" : "tcp", world_.map().name,
                 policy_->name(), config_.tick_rate, config_.bots, pool_.threads());
    if (config_.role == "gateway") {
        feed_ = std::make_unique<WorldFeed>(
            io_, config_, scaleout::world_key(world_.map(), world_settings(config_)),
            [this] { on_world_tick(); },
            [this] {
                if (io_loop_ != nullptr) { // set before start(), never changed after
                    io_loop_->wake();
                }
            });
        spdlog::info("gateway of world '{}' at {}: ticks come from the world process",
                     config_.world_name, config_.nats_url);
    }
    if (!config_.trace_file.empty()) {
        trace::TraceHeader header;
        header.map = world_.map().name;
        header.tick_rate = config_.tick_rate;
        header.policy = std::string(policy_->name());
        header.lookahead_ticks = lookahead_ticks(config_);
        const auto& occluders = world_.map().occluders;
        for (std::size_t i = 0; i < occluders.size(); ++i) {
            header.occluders.push_back({static_cast<std::uint32_t>(i), occluders[i].planes()});
        }
        trace_ = std::make_unique<trace::TraceWriter>();
        std::string error;
        if (!trace_->open(config_.trace_file, header, error)) {
            throw std::runtime_error(error);
        }
        spdlog::info("writing a replication trace to {} (every {} tick(s))", config_.trace_file,
                     config_.trace_every);
    }
    accept_next();
    started_ = true;
    last_skip_log_ = Clock::now();
    schedule_ = TickSchedule(last_skip_log_, tick_period_);
    if (!feed_) {
        schedule_tick(); // a gateway's ticks start as the world's arrive
    }
    return port;
}

void Server::accept_next() {
    acceptor_.async_accept(
        [this](const boost::system::error_code& ec, asio::ip::tcp::socket socket) {
            if (ec) {
                if (ec != asio::error::operation_aborted && !shutting_down_) {
                    spdlog::warn("accept failed: {}", ec.message());
                    accept_next();
                }
                return;
            }
            const std::uint32_t id = take_client_id();
            auto session = std::make_shared<Session>(std::move(socket), id, config_,
                                                     static_cast<ConnectionHost&>(*this));
            session->start();
            open_connection(session);
            accept_next();
        });
}

std::uint32_t Server::take_client_id() {
    return take_free_client_id(next_client_id_, [this](std::uint32_t id) {
        return sessions_.contains(id) || clients_.contains(id);
    });
}

void Server::open_connection(const std::shared_ptr<Connection>& connection) {
    sessions_[connection->client_id()] = connection;
    ++stats_.clients_accepted;
    // Whether the server is full is the hello's to decide (on_hello): a connection that
    // has not said one takes no client's place, only one of the pending connections'. A
    // UDP connection opens with its hello (its address proven first): it never waits.
    if (connection->transport() == Transport::udp) {
        return;
    }
    if (pending_.size() >= static_cast<std::size_t>(config_.max_pending_connections)) {
        // The oldest waiting connection of the source holding the most makes room: many
        // sources' silent connections cannot keep a newcomer out, which refusing the
        // newcomer would let them.
        const auto most = std::max_element(
            pending_by_source_.begin(), pending_by_source_.end(),
            [](const auto& a, const auto& b) { return a.second.size() < b.second.size(); });
        const std::uint32_t oldest = most->second.front();
        const std::size_t held = most->second.size();
        release_pending(oldest);
        if (const auto it = sessions_.find(oldest); it != sessions_.end()) {
            it->second->disconnect(pb::DISCONNECT_REASON_TRY_AGAIN,
                                   std::to_string(config_.max_pending_connections) +
                                       " connections were waiting for their hello, " +
                                       std::to_string(held) + " of them from this address");
        }
    }
    std::deque<std::uint32_t>& waiting = pending_by_source_[connection->source()];
    if (waiting.size() >= static_cast<std::size_t>(config_.max_pending_per_source)) {
        connection->hurry_hello(std::chrono::milliseconds(ServerConfig::kCrowdedHelloMs));
    }
    waiting.push_back(connection->client_id());
    pending_.emplace(connection->client_id(), connection->source());
}

void Server::release_pending(std::uint32_t id) {
    const auto it = pending_.find(id);
    if (it == pending_.end()) {
        return;
    }
    const auto source = pending_by_source_.find(it->second);
    std::deque<std::uint32_t>& waiting = source->second;
    waiting.erase(std::find(waiting.begin(), waiting.end(), id));
    if (waiting.empty()) {
        pending_by_source_.erase(source);
    }
    pending_.erase(it);
}

void Server::schedule_tick() {
    // Ticks missed by a whole period or more are dropped, counted and logged (see
    // TickSchedule); the next tick then runs at once.
    const auto now = Clock::now();
    if (const std::uint64_t missed = schedule_.skip_missed(now); missed > 0) {
        const bool first = stats_.skipped_ticks == 0;
        stats_.skipped_ticks += missed;
        skipped_since_log_ += missed;
        if (first || now - last_skip_log_ >= std::chrono::seconds(10)) {
            spdlog::warn("tick loop behind: skipped {} tick(s) in the last {:.1f} s ({} in all); "
                         "ticks take longer than the {:.1f} ms period",
                         skipped_since_log_,
                         std::chrono::duration<double>(now - last_skip_log_).count(),
                         stats_.skipped_ticks,
                         std::chrono::duration<double, std::milli>(tick_period_).count());
            last_skip_log_ = now;
            skipped_since_log_ = 0;
        }
    }
    tick_timer_.expires_at(schedule_.next_due());
    tick_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (ec || shutting_down_) {
            return;
        }
        start_tick();
    });
}

void Server::on_world_tick() {
    if (started_ && !shutting_down_ && !phase_running_) {
        start_tick(); // else the hand-over starts it
    }
}

void Server::start_tick() {
    // Serial, on the I/O thread: nothing of the previous tick is in flight.
    std::optional<TakenTick> arrived;
    if (feed_) {
        arrived = feed_->take_newest();
        if (!arrived) {
            return; // taken by an earlier call: the next arrival starts the next tick
        }
        if (arrived->restart) {
            end_sessions_of_a_past_world(*arrived->restart);
        }
        if (!arrived->abandoned.empty()) {
            end_sessions_without_a_player(arrived->abandoned);
        }
    }
    tick_start_ = Clock::now();
    if (!feed_ && schedule_.start_tick(tick_start_)) {
        ++stats_.late_ticks;
    }
    tick_ = feed_ ? arrived->number : tick_ + 1;
    apply_joins();
    apply_inputs();
    if (feed_) {
        tick_published_ns_ = arrived->tick.published_ns;
        scaleout::apply_world_tick(std::move(arrived->tick), world_);
    } else {
        const float dt = 1.0f / static_cast<float>(config_.tick_rate);
        // The moves on the pool's threads (idle between phases), this thread taking part.
        world_.step(dt, [this](std::size_t count, const std::function<void(std::size_t)>& body) {
            pool_.run(count, body);
        });
    }
    prepare_client_ticks(); // may disconnect slow clients
    culling_start_ = Clock::now();
    stats_.prepare_duration.observe(
        std::chrono::duration<double>(culling_start_ - tick_start_).count());
    policy_->begin_tick(world_, tick_);
    hearing_.begin_tick(world_);
    shared_poses_.compute(world_, quantization(config_));
    // The parallel phase: on the pool's threads; this thread goes back to the sockets.
    phase_running_ = true;
    phase_work_.emplace(io_.get_executor());
    culling_budget_.enabled = config_.culling_budget > 0.0;
    culling_budget_.deadline = tick_start_ + std::chrono::duration_cast<Clock::duration>(
                                                 tick_period_ * config_.culling_budget);
    culling_budget_.cheapest.store(0, std::memory_order_relaxed);
    start_client_ticks(
        world_, *policy_, tick_, client_ticks_, pool_,
        [this](std::exception_ptr error) {
            const auto phase_end = Clock::now();
            asio::post(io_, [this, phase_end, error] { finish_tick(phase_end, error); });
            if (io_loop_ != nullptr) {
                io_loop_->wake();
            }
        },
        &culling_budget_);
}

void Server::finish_tick(Clock::time_point phase_end, std::exception_ptr error) {
    const auto handover_start = Clock::now();
    stats_.handover_wait.observe(std::chrono::duration<double>(handover_start - phase_end).count());
    phase_running_ = false;
    phase_work_.reset();
    if (error) {
        std::rethrow_exception(error); // a bug in a policy: out of io_context::run()
    }
    stats_.culling_duration.observe(
        std::chrono::duration<double>(phase_end - culling_start_).count());
    stats_.cheapest_client_ticks += culling_budget_.cheapest.load(std::memory_order_relaxed);
    send_snapshots();
    if (const std::uint64_t now = scaleout::monotonic_ns();
        feed_ && tick_published_ns_ != 0 && now > tick_published_ns_) {
        // Another host's clock can be ahead: only a later `now` is a hop.
        const double hop_s = static_cast<double>(now - tick_published_ns_) * 1e-9;
        stats_.world_hop.observe(hop_s);
        if (stats_.world_hop_us.size() < kMaxTickSamples) {
            stats_.world_hop_us.push_back(hop_s * 1e6);
        }
    }
    if (trace_ && !shutting_down_ && tick_ % static_cast<std::uint64_t>(config_.trace_every) == 0) {
        write_trace_tick();
    }
    tbvs_alive_ = policy_->tbvs_alive();
    apply_leaves();
    ++stats_.ticks;
    const auto handover_end = Clock::now();
    stats_.handover_duration.observe(
        std::chrono::duration<double>(handover_end - handover_start).count());
    const double cost_s =
        std::chrono::duration<double>((phase_end - tick_start_) + (handover_end - handover_start))
            .count();
    stats_.tick_duration.observe(cost_s);
    if (stats_.tick_cost_us.size() < kMaxTickSamples) {
        stats_.tick_cost_us.push_back(cost_s * 1e6);
    }
    if (shutting_down_) {
        maybe_finish_shutdown();
    } else if (!feed_) {
        schedule_tick();
    } else if (feed_->tick_waiting()) {
        asio::post(io_, [this] { on_world_tick(); }); // arrived during the phase
    }
}

void Server::end_sessions_of_a_past_world(const WorldRestart& restart) {
    std::vector<std::shared_ptr<Connection>> ending;
    for (auto& [id, client] : clients_) {
        if (client.session->entity_id() != 0) {
            client.session->set_entity_id(0);
            ending.push_back(client.session);
        }
    }
    // Not while iterating: a disconnect may close the session at once.
    const std::string why = fmt::format("the world process restarted (instance {:016x} after "
                                        "{:016x}): your player is gone; connect again",
                                        restart.new_instance, restart.old_instance);
    for (const auto& session : ending) {
        session->disconnect(pb::DISCONNECT_REASON_WORLD_RESTARTED, why);
    }
    spdlog::warn("world '{}' restarted (instance {:016x} after {:016x}): {} client session(s) "
                 "ended with world_restarted, their entity ids void in the new world",
                 config_.world_name, restart.new_instance, restart.old_instance, ending.size());
}

void Server::end_sessions_without_a_player(std::span<const std::uint32_t> entity_ids) {
    std::vector<std::shared_ptr<Connection>> ending;
    for (auto& [id, client] : clients_) {
        const std::uint32_t entity = client.session->entity_id();
        if (entity != 0 && std::binary_search(entity_ids.begin(), entity_ids.end(), entity)) {
            client.session->set_entity_id(0); // its leave is sent: none at its close
            ending.push_back(client.session);
        }
    }
    // Not while iterating: a disconnect may close the session at once.
    for (const auto& session : ending) {
        session->disconnect(pb::DISCONNECT_REASON_TRY_AGAIN,
                            "the world process no longer holds this player's entity id for "
                            "this gateway (it took the gateway for lost and gave its ids up): "
                            "connect again for a new one");
    }
    spdlog::warn("world '{}' no longer holds {} entity id(s) of this gateway's players (their "
                 "joins went unanswered {} times: it forgot this gateway while it was cut "
                 "off): {} client session(s) ended with try_again",
                 config_.world_name, entity_ids.size(), GatewayIds::kJoinResends + 1,
                 ending.size());
}

void Server::apply_joins() {
    // In hello order, so entity ids (reserved at hello) stay increasing in the world.
    for (const std::uint32_t id : pending_joins_) {
        const auto it = clients_.find(id);
        if (it == clients_.end() || !it->second.session->active()) {
            continue; // left before its first tick: its id is never spawned
        }
        const std::uint32_t entity = it->second.session->entity_id();
        if (feed_) {
            outgoing_ids_.push_back(entity); // spawned at the world's next step
        } else {
            world_.spawn_reserved(entity);
        }
        policy_->add_viewer(id, entity);
        it->second.viewing = entity;
    }
    pending_joins_.clear();
    if (feed_) {
        feed_->send_joins(outgoing_ids_);
        outgoing_ids_.clear();
    }
}

void Server::apply_inputs() {
    // Each client's latest input since the last tick start (what the step would have
    // seen had it been applied on arrival).
    for (auto& [id, client] : clients_) {
        const pb::ClientInput& input = client.input;
        if (feed_ && !client.session->active()) {
            continue; // leaving; after a world restart its id is another's
        }
        if (feed_ && (client.input_pending || client.fire_pending)) {
            // For the world process, which applies it at its next step.
            outgoing_inputs_.push_back(
                {client.session->entity_id(),
                 glm::clamp(glm::vec3(input.move_x(), input.move_y(), 0.0f), -1.0f, 1.0f),
                 input.jump(), client.fire_pending, input.view_yaw(), input.view_pitch()});
            client.watch = input.watch();
            client.input_pending = false;
            client.fire_pending = false;
            continue;
        }
        if (client.input_pending) {
            world_.set_player_input(client.session->entity_id(),
                                    glm::vec3(input.move_x(), input.move_y(), input.move_z()),
                                    input.jump(), input.view_yaw(), input.view_pitch());
            client.watch = input.watch();
            client.input_pending = false;
        }
        if (client.fire_pending) {
            world_.fire(client.session->entity_id());
            client.fire_pending = false;
        }
    }
    if (feed_) {
        feed_->send_inputs(outgoing_inputs_);
        outgoing_inputs_.clear();
    }
}

void Server::prepare_client_ticks() {
    client_ticks_.clear();
    tick_clients_.clear();
    const auto now = Clock::now();
    for (auto& [id, client] : clients_) {
        Connection& session = *client.session;
        if (!session.active()) {
            continue;
        }
        const interest::Entity* self = world_.find(session.entity_id());
        if (self == nullptr) {
            continue;
        }
        // false: its previous snapshot is still unsent; this one is dropped (latest
        // wins). May disconnect the client as too slow.
        const bool build = session.offer_snapshot(now, tick_);
        if (!session.active()) {
            continue;
        }
        const interest::Entity& viewed = viewed_entity(client, *self);
        if (viewed.id != client.viewing) { // a spectator switched: before begin_tick()
            policy_->remove_viewer(id);
            policy_->add_viewer(id, viewed.id);
            client.viewing = viewed.id;
        }
        stats_.spectating_client_ticks += viewed.id != self->id ? 1 : 0;
        ClientTick job;
        job.viewer = interest::viewer_of(world_, id, viewed);
        job.viewer.entity_id = self->id; // its own entity, sent whatever it watches
        job.replication = &client.replication;
        job.interest = &client.interest;
        job.envelope = &client.envelope;
        job.frame = &client.frame;
        job.columns = &client.columns;
        job.acked_tick = session.acked_tick();
        job.poses = &shared_poses_;
        job.build = build;
        job.audit = client.audit_every > 0 && tick_ % client.audit_every == 0;
        job.network_lod = config_.network_lod;
        job.hearing = &hearing_;
        job.heard = &client.heard;
        client_ticks_.push_back(job);
        tick_clients_.push_back(&client);
    }
}

const interest::Entity& Server::viewed_entity(const Client& client,
                                              const interest::Entity& self) const {
    if (client.watch == 0 || client.watch == self.id) {
        return self;
    }
    const interest::Entity* watched = world_.find(client.watch);
    return watched != nullptr ? *watched : self;
}

void Server::send_snapshots() {
    // A client with nothing queued has its frame handed to the kernel directly, on the
    // pool's threads and this one (each loopback write also pays for the receiver's
    // side, so one thread writing 500 frames is a large serial share of the tick); the
    // others, and whatever the kernel did not take, go through their session's queue.
    direct_writes_.clear();
    for (std::size_t i = 0; i < client_ticks_.size(); ++i) {
        const ClientTick& job = client_ticks_[i];
        if (!job.build) {
            continue;
        }
        Client& client = *tick_clients_[i];
        if (!client.session->active()) {
            continue; // left or kicked during the phase
        }
        stats_.entity_updates_sent += client.replication.last_updates();
        stats_.heard_entities_sent += client.heard;
        ++stats_.snapshots_sent;
        if (client.replication.acked()) {
            const protocol::AckedSnapshotCounts& coded = client.replication.last_acked();
            ++(coded.coded_against_baseline ? stats_.acked_snapshots_against_baseline
                                            : stats_.acked_snapshots_whole);
            stats_.acked_baseline_age_ticks += coded.baseline_age;
            stats_.acked_enters_deferred += client.replication.last_deferred();
            stats_.acked_updates_deferred += client.replication.last_updates_deferred();
        }
        if (client.session->writable_now()) {
            direct_writes_.push_back(&client);
        } else {
            client.session->send_snapshot_frame(client.frame);
        }
    }
    // Jobs of up to kMaxClientsPerJob clients, as many as the pool has threads when
    // fewer: over UDP a job's datagrams go in one DatagramBatch (as few system calls as
    // it takes); a transport that does not batch writes each frame (write_now()).
    constexpr std::size_t kMaxClientsPerJob = 32;
    const std::size_t writes = direct_writes_.size();
    const auto threads = static_cast<std::size_t>(std::max(1, pool_.threads()));
    const std::size_t per_job =
        std::clamp<std::size_t>((writes + threads - 1) / threads, 1, kMaxClientsPerJob);
    direct_written_.assign(writes, 0);
    pool_.run((writes + per_job - 1) / per_job, [this, per_job](std::size_t job) {
        thread_local DatagramBatch batch; // its memory kept from tick to tick
        batch.clear();
        const std::size_t from = job * per_job;
        const std::size_t to = std::min(direct_writes_.size(), from + per_job);
        std::array<bool, kMaxClientsPerJob> queued{};
        for (std::size_t k = from; k < to; ++k) {
            Client& client = *direct_writes_[k];
            queued[k - from] = client.session->queue_now(client.frame, batch);
            if (!queued[k - from]) {
                direct_written_[k] = client.session->write_now(client.frame);
            }
        }
        batch.send();
        for (std::size_t k = from; k < to; ++k) {
            if (queued[k - from]) {
                direct_written_[k] = direct_writes_[k]->session->finish_queued(batch);
            }
        }
    });
    for (std::size_t k = 0; k < direct_writes_.size(); ++k) {
        Client& client = *direct_writes_[k];
        if (client.session->finish_write_now(client.frame, direct_written_[k])) {
            ++stats_.snapshot_writes_queued;
        }
    }
}

void Server::apply_leaves() {
    if (phase_running_) {
        return; // the jobs still read the world and the policy: at the hand-over
    }
    for (const std::uint32_t id : pending_leaves_) {
        const auto it = sessions_.find(id);
        if (it != sessions_.end() && it->second->entity_id() != 0) {
            if (feed_) {
                // Removed at the world's next step; the mirror follows its next tick.
                outgoing_ids_.push_back(it->second->entity_id());
            } else {
                world_.remove(it->second->entity_id()); // not spawned yet: nothing to remove
            }
        }
        policy_->remove_viewer(id);
        clients_.erase(id);
        sessions_.erase(id); // its pending place went in on_closed()
    }
    pending_leaves_.clear();
    if (feed_) {
        feed_->send_leaves(outgoing_ids_);
        outgoing_ids_.clear();
    }
    maybe_finish_shutdown();
}

void Server::write_trace_tick() {
    trace::TraceTick& t = trace_tick_;
    t.t = tick_;
    t.entities.clear();
    for (const interest::Entity& e : world_.entities()) {
        t.entities.push_back({e.id, world_.box_of(e)});
    }
    t.clients.clear();
    for (const auto& [id, client] : clients_) {
        const Connection& session = *client.session;
        const interest::Entity* self = world_.find(session.entity_id());
        if (!session.active() || self == nullptr) {
            continue;
        }
        // A spectator's eye (and team) are those of the entity it watches.
        const interest::Entity* viewed = world_.find(client.viewing);
        if (viewed == nullptr) {
            viewed = self;
        }
        trace::TraceClient& c = t.clients.emplace_back();
        c = {id, session.entity_id(), world_.eye_of(*viewed), client.replication.known(),
             world_.arrival_eye_of(*viewed)};
        if (viewed->team != visibility::kNoTeam) { // teammates are sent for their team
            for (const interest::Entity& e : world_.entities()) {
                if (e.team == viewed->team && e.id != viewed->id) {
                    c.always.push_back(e.id);
                }
            }
        }
        // This tick's heard-only entities (its job's answer) that the client knows: a
        // client whose snapshot was skipped still knows what it was last sent.
        for (const interest::Interest& i : client.interest) {
            if (i.tier == interest::kHeardTier &&
                std::binary_search(c.replicated.begin(), c.replicated.end(), i.id)) {
                c.heard.push_back(i.id);
            }
        }
    }
    trace_->write_tick(t);
}

void Server::on_hello(Connection& session, const pb::ClientHello& client_hello) {
    if (shutting_down_) {
        session.disconnect(pb::DISCONNECT_REASON_SERVER_SHUTDOWN, "server is shutting down");
        return;
    }
    if (token_key_) {
        const auto& token = client_hello.connect_token();
        const auto check = protocol::verify_connect_token(
            *token_key_,
            std::span(reinterpret_cast<const std::uint8_t*>(token.data()), token.size()),
            protocol::unix_now_s());
        if (check.status != protocol::TokenStatus::valid) {
            session.disconnect(pb::DISCONNECT_REASON_UNAUTHORIZED, check.why);
            return;
        }
        // One connection per client id: a second one with the same token is refused,
        // so a leaked token cannot take over a player who is connected.
        const auto [it, inserted] =
            token_clients_.try_emplace(check.token.client_id, session.client_id());
        if (!inserted) {
            session.disconnect(pb::DISCONNECT_REASON_UNAUTHORIZED,
                               "client " + std::to_string(check.token.client_id) +
                                   " is already connected");
            return;
        }
        session.set_token_client_id(check.token.client_id);
    }
    if (static_cast<int>(clients_.size()) >= config_.max_clients) {
        session.disconnect(pb::DISCONNECT_REASON_SERVER_FULL,
                           "server holds " + std::to_string(config_.max_clients) +
                               " clients at most");
        return;
    }
    // The entity is spawned (and the policy told) at the next tick start: a phase may
    // be reading the world now. The client learns its id at once.
    const std::uint32_t entity = take_entity_id(session);
    if (entity == 0) {
        return; // refused
    }
    session.set_entity_id(entity);
    pb::Envelope reply;
    auto& hello = *reply.mutable_server_hello();
    hello.set_protocol_version(protocol::kProtocolVersion);
    hello.set_client_id(session.client_id());
    hello.set_entity_id(entity);
    hello.set_team(world_.team_for(entity));
    hello.set_tick_rate(static_cast<std::uint32_t>(config_.tick_rate));
    hello.set_map_name(world_.map().name);
    hello.set_server_tick(tick_);
    hello.set_max_speed(config_.max_speed);
    protocol::to_message(quantization(config_), *hello.mutable_quantization());
    session.send(reply);
    session.mark_active();
    auto it = sessions_.find(session.client_id());
    Client& client =
        clients_
            .try_emplace(session.client_id(),
                         Client{.session = it->second,
                                .replication = ReplicationState(
                                    quantization(config_), session.transport() == Transport::udp)})
            .first->second;
    client.audit_every = client_hello.audit_every_ticks();
    release_pending(session.client_id());
    pending_joins_.push_back(session.client_id());
    spdlog::debug("client {} '{}' from {} joined as entity {}", session.client_id(), session.name(),
                  session.remote(), entity);
}

std::uint32_t Server::take_entity_id(Connection& session) {
    if (!feed_) {
        const std::uint32_t entity = world_.reserve_player();
        if (entity == 0) {
            session.disconnect(pb::DISCONNECT_REASON_SERVER_FULL,
                               "the world's 32-bit entity ids are used up");
        }
        return entity;
    }
    // A gateway without an id yet will have one shortly (ids asked for, or a world
    // restart being taken): the client is told to try again, not that the server is
    // full (docs/scale-out.md, "Entity ids").
    std::string why_not;
    const std::uint32_t entity = feed_->take_entity_id(&why_not);
    if (entity == 0) {
        session.disconnect(pb::DISCONNECT_REASON_TRY_AGAIN, why_not + ": connect again shortly");
    }
    return entity;
}

void Server::on_input(Connection& session, const pb::ClientInput& input) {
    // Kept until the next tick start: a phase may be reading the world now.
    const auto it = clients_.find(session.client_id());
    if (it != clients_.end()) {
        it->second.input = input;
        it->second.input_pending = true;
        it->second.fire_pending = it->second.fire_pending || input.fire();
    }
}

void Server::add_session_counts(const Connection& session, ServerStats& stats) {
    stats.bytes_sent += session.bytes_sent();
    stats.bytes_received += session.bytes_received();
    stats.snapshots_dropped += session.snapshots_dropped();
    stats.snapshots_paced.lagging += session.snapshots_paced().lagging;
    stats.snapshots_paced.behind += session.snapshots_paced().behind;
    stats.inputs_dropped += session.inputs_dropped();
    stats.inputs_clamped += session.inputs_clamped();
}

void Server::on_closed(Connection& session) {
    const std::uint32_t id = session.client_id();
    add_session_counts(session, stats_);
    ++stats_.disconnects[protocol::disconnect_reason_name(session.close_reason())];
    stats_.peak_queued_bytes = std::max(stats_.peak_queued_bytes, session.peak_queued_bytes());
    if (session.token_client_id() != 0) {
        const auto it = token_clients_.find(session.token_client_id());
        if (it != token_clients_.end() && it->second == id) {
            token_clients_.erase(it);
        }
    }
    release_pending(id); // io thread, as every use of the pending connections
    // The entity, the policy's state and the client's buffers go when no phase runs:
    // a job may be using them now.
    pending_leaves_.push_back(id);
    asio::post(io_, [this] { apply_leaves(); }); // not from inside the session's handler
}

Readiness Server::readiness() const {
    if (shutting_down_) {
        return {false, "shutting down"};
    }
    if (!started_) {
        return {false, "not started"};
    }
    if (stats_.ticks == 0) {
        return {false, "waiting for the first tick"};
    }
    return {true, {}};
}

void Server::shutdown(std::function<void()> on_done) {
    if (shutting_down_) {
        return;
    }
    shutting_down_ = true;
    on_shutdown_done_ = std::move(on_done);
    spdlog::info("shutting down: {} connection(s) to close", sessions_.size());
    if (trace_) {
        trace_->close();
        spdlog::info("trace: {} tick(s) written to {}", trace_->ticks_written(),
                     config_.trace_file);
    }
    boost::system::error_code ec;
    acceptor_.close(ec);
    tick_timer_.cancel();
    const auto open = sessions_; // copy: disconnect may close synchronously
    for (const auto& [id, session] : open) {
        session->disconnect(pb::DISCONNECT_REASON_SERVER_SHUTDOWN, "server shutting down");
    }
    if (udp_) {
        udp_->stop(); // its connections closed at once, their reasons sent
    }
    asio::post(io_, [this] { maybe_finish_shutdown(); });
}

void Server::maybe_finish_shutdown() {
    if (shutting_down_ && sessions_.empty() && on_shutdown_done_) {
        auto done = std::move(on_shutdown_done_);
        on_shutdown_done_ = nullptr;
        done();
    }
}

} // namespace dsoc::server
