#pragma once
// The dsoc game server: accepts clients, runs a fixed-rate tick loop, moves every
// entity authoritatively and sends each client the snapshot its interest policy
// allows.
//
// Thread model. Two kinds of thread, and who may touch what:
// - The I/O thread: the one thread that runs the io_context given to the server (run
//   it on exactly one thread). It owns sockets, sessions, the client tables, the
//   world, the policy and the statistics, and does all I/O: accepts, reads, hellos
//   and connect-token checks, pings, writes, the /metrics endpoint on the same
//   io_context. It also runs the serial ends of each tick: the tick start (joins,
//   inputs, movement, choosing which clients get a snapshot, the policy's
//   begin_tick, this tick's quantized poses) and the hand-over (queueing the finished
//   snapshot frames, the trace, leaves).
// - The worker pool: config.threads threads of its own (0: one per core). Between
//   tick start and hand-over it runs the parallel phase - every client's interest
//   evaluation and snapshot (client_tick.hpp) - while the I/O thread keeps serving
//   sockets. The jobs read the world, the policy's per-tick state and this tick's
//   poses, and write only their own client's replication state, interest set,
//   envelope and frame.
// While a phase is in flight the I/O thread therefore never writes what the jobs
// read: a hello reserves an entity id and is answered at once, but the entity is
// spawned and the policy told at the next tick start; an input is kept as the
// client's latest and handed to the world at the next tick start; a closed client
// (quit, kicked as too slow, anything) keeps its entity, its policy state and its
// per-client buffers until the hand-over (or at once when no phase runs). /metrics
// reads only I/O-thread state (the TBV count is the one taken at the last hand-over).
// One tick at a time: the next tick is scheduled at the hand-over.
//
// As an interest gateway (config.role "gateway", docs/scale-out.md) the server does not
// move the world: a tick starts when the world process's next tick arrives over NATS
// (the newest, when several did), the world is mirrored from it, and the joins,
// inputs and leaves go to the world process instead of the world (they take effect
// at its next step). Hellos are answered with ids the world reserved for this gateway;
// while it has none (asked for, or a world restart being taken) they are refused with
// `try_again`.
// When the world process restarts, every session that holds an entity id ends with
// `world_restarted` (the new world hands the same ids to others); its clients connect
// again. The server's tick numbers keep increasing across such restarts.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/hearing.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/client_tick.hpp"
#include "dsoc/server/io_loop.hpp"
#include "dsoc/server/metrics.hpp"
#include "dsoc/server/metrics_endpoint.hpp"
#include "dsoc/server/replication_state.hpp"
#include "dsoc/server/server_config.hpp"
#include "dsoc/server/session.hpp"
#include "dsoc/server/tick_schedule.hpp"
#include "dsoc/server/udp_endpoint.hpp"
#include "dsoc/server/world_feed.hpp"
#include "dsoc/trace/trace_writer.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <boost/asio/executor_work_guard.hpp>

#include <chrono>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace dsoc::server {

/// Totals since start; read them on the io_context thread or after run() returned.
struct ServerStats {
    std::uint64_t ticks = 0;
    /// Ticks that started more than one period after they were due, or in place of
    /// skipped ones.
    std::uint64_t late_ticks = 0;
    /// Ticks never run: when a tick starts a whole period or more after it was due, the
    /// missed ones are dropped (not run back to back) and counted here.
    std::uint64_t skipped_ticks = 0;
    std::uint64_t bytes_sent = 0;     ///< to clients, frame headers included
    std::uint64_t bytes_received = 0; ///< from clients, frame headers included
    std::uint64_t snapshots_sent = 0;
    std::uint64_t entity_updates_sent = 0; ///< enters + updates
    /// Snapshots the kernel did not take whole at the hand-over (the client's socket
    /// buffer was full): the rest waited in the session's queue.
    std::uint64_t snapshot_writes_queued = 0;
    std::uint64_t clients_accepted = 0;
    std::map<std::string, std::uint64_t> disconnects; ///< by reason name
    // Of closed connections (render_metrics() adds the live ones).
    std::uint64_t snapshots_dropped = 0; ///< not built: the client's previous one was unsent
    SnapshotPaceCounts snapshots_paced;  ///< of those, skipped by UDP clients' pace
    std::uint64_t inputs_dropped = 0;    ///< client messages over max_inputs_per_second
    std::uint64_t inputs_clamped = 0;    ///< inputs with an out-of-range field clamped
    std::size_t peak_queued_bytes = 0;   ///< largest send queue of any client
    /// Per tick, work time in microseconds: the tick start on the I/O thread, the
    /// parallel phase's wall time and the hand-over (not the wait for the timer, nor
    /// for the I/O thread to take the hand-over up).
    std::vector<double> tick_cost_us;
    DurationHistogram tick_duration; ///< the same work time, for /metrics
    /// Per tick, wall time of the policy's begin_tick and the parallel phase (until the
    /// last job returns): interest evaluation (culling) and snapshot building of every
    /// client on the worker pool.
    DurationHistogram culling_duration;
    /// Per tick, wall time on the I/O thread before the parallel phase: joins, inputs,
    /// the world's step (on the pool), snapshot offers and the shared preparation.
    DurationHistogram prepare_duration;
    /// Per tick, wall time of the hand-over after the phase: the snapshot frames handed
    /// to the sockets (on the pool), the trace, the leaves.
    DurationHistogram handover_duration;
    /// Per tick, wall time from the parallel phase's end to the hand-over's start: how
    /// long the finished snapshots waited for the I/O thread (busy with sockets, or
    /// gathering events without a wake; io_loop.hpp). Not part of the tick's work.
    DurationHistogram handover_wait;
    /// Client-ticks served the policy's cheapest answer: their turn came after the
    /// tick's culling budget (ServerConfig::culling_budget).
    std::uint64_t cheapest_client_ticks = 0;
    /// Client-ticks sent another entity's view (spectators: ClientInput.watch).
    std::uint64_t spectating_client_ticks = 0;
    /// Entities in snapshots sent only because the client hears them (the heard tier),
    /// summed over the client-ticks that were sent.
    std::uint64_t heard_entities_sent = 0;
    /// Acknowledged-delta snapshots sent (UDP clients), coded against an acknowledged
    /// frame or whole (no acknowledgement, or one too old), and the sum of the former's
    /// baseline ages in ticks: how late acknowledgements are.
    std::uint64_t acked_snapshots_against_baseline = 0;
    std::uint64_t acked_snapshots_whole = 0;
    std::uint64_t acked_baseline_age_ticks = 0;
    /// Entities a client was to know that did not enter its snapshot for want of room
    /// (protocol::kMaxEntersPerSnapshot): they enter in its later snapshots.
    std::uint64_t acked_enters_deferred = 0;
    /// Update entries left out of a client's snapshot for want of room (its datagrams'
    /// bytes): the entity stays known, at its prediction until a later snapshot's entry.
    std::uint64_t acked_updates_deferred = 0;
    /// Role gateway, per tick: from the world process encoding the tick to this gateway
    /// handing the tick's last snapshot to the kernel (both clocks CLOCK_MONOTONIC, so
    /// meaningful when both run on one host). Microseconds, and as a histogram.
    std::vector<double> world_hop_us;
    DurationHistogram world_hop;
};

class Server final : private ConnectionHost {
public:
    /// `config` must have passed validate(); `map` is the loaded config.map.
    Server(boost::asio::io_context& io, ServerConfig config, std::shared_ptr<const maps::Map> map);
    /// Waits for a parallel phase in flight (destroy the server after io_context::run()
    /// returned, or from the I/O thread).
    ~Server() override;
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    /// Binds, listens and starts the tick loop: TCP on config.port, and UDP on the same
    /// port number when config.udp. Returns the bound port (useful with port 0). Throws
    /// boost::system::system_error when the address cannot be bound, std::runtime_error when the
    /// trace file or the token key cannot be read.
    std::uint16_t start();

    /// The loop that runs the I/O thread, when it gathers events (io_loop.hpp): woken
    /// when a tick's parallel phase ends, so that the hand-over does not wait out a
    /// gather. Set before start(); null (the default) for a plain io_context::run().
    void set_io_loop(IoLoop* loop) { io_loop_ = loop; }

    /// Stops accepting, stops ticking, tells every client `server_shutdown`, and lets
    /// the connections drain; io_context::run() then returns once all are closed.
    /// `on_done` (optional) runs when the last connection has closed.
    void shutdown(std::function<void()> on_done = {});

    [[nodiscard]] const ServerStats& stats() const { return stats_; }
    /// The UDP endpoint (null without config.udp, or before start()); read it on the
    /// io_context thread or after run() returned.
    [[nodiscard]] const UdpEndpoint* udp_endpoint() const { return udp_.get(); }
    [[nodiscard]] const ServerConfig& config() const { return config_; }
    [[nodiscard]] std::size_t session_count() const { return sessions_.size(); }
    /// The world process's feed (role "gateway", after start()), else null.
    [[nodiscard]] const WorldFeed* world_feed() const { return feed_.get(); }
    [[nodiscard]] std::uint64_t tick() const { return tick_; }
    /// Whether the server takes players, for /readyz: from the end of its first tick
    /// (start() ran, the tick loop runs) until shutdown() begins. Call on the io_context
    /// thread.
    [[nodiscard]] Readiness readiness() const;
    /// Everything an operator watches, in the Prometheus text format (what /metrics
    /// serves; the names are listed in docs/operations.md). Totals include the live
    /// connections. Call on the io_context thread.
    [[nodiscard]] std::string render_metrics() const;

private:
    struct Client {
        std::shared_ptr<Connection> session;
        ReplicationState replication;             // written by this client's job during a phase
        std::vector<interest::Interest> interest; // this tick's set, written by the job
        protocol::pb::Envelope envelope;          // this tick's snapshot, written by the job
        std::uint32_t audit_every = 0;            // ClientHello.audit_every_ticks
        std::vector<std::uint8_t> frame;          // this tick's snapshot frame, written by the job
        protocol::UpdateColumns columns;          // its update entries in wire form (the job's)
        protocol::pb::ClientInput input;          // the latest input, for the next tick start
        bool input_pending = false;               // `input` not handed to the world yet
        std::uint32_t heard = 0;                  // this tick's entities sent only because heard
        bool fire_pending = false; // an input since the last tick start fired (not only the latest)
        std::uint32_t watch = 0;   // ClientInput.watch of the latest input (0: its own view)
        std::uint32_t viewing = 0; // the entity the policy views from for it (0: not yet)
    };

    void accept_next();
    void schedule_tick();
    /// Role gateway: a world tick arrived (on the I/O thread).
    void on_world_tick();
    void start_tick();
    void finish_tick(std::chrono::steady_clock::time_point phase_end, std::exception_ptr error);
    /// Role gateway, when the world process restarted: every client's entity id is void,
    /// so each session ends with world_restarted and loses its id at once (nothing of it,
    /// no input and no leave, reaches the new world, where that id is another's).
    void end_sessions_of_a_past_world(const WorldRestart& restart);
    /// Role gateway, when the world no longer holds `entity_ids` for this gateway (their
    /// joins were given up, their leaves sent: TakenTick::abandoned): each session holding
    /// one ends with try_again and loses its id at once; its client connects again for a
    /// fresh one.
    void end_sessions_without_a_player(std::span<const std::uint32_t> entity_ids);
    /// A hello's entity id (reserved in the world, or from the gateway's blocks), or 0
    /// after ending `session` with the reason: try_again on a gateway that has none yet,
    /// server_full when the world's ids are used up.
    std::uint32_t take_entity_id(Connection& session);
    void apply_joins();
    void apply_inputs();
    void prepare_client_ticks();
    /// The entity whose view `client` (whose own entity is `self`) is sent: the one it
    /// watches (ClientInput.watch) while that is in the world, else its own.
    [[nodiscard]] const interest::Entity& viewed_entity(const Client& client,
                                                        const interest::Entity& self) const;
    void send_snapshots();
    void apply_leaves();
    void maybe_finish_shutdown();
    void write_trace_tick();

    void on_hello(Connection& session, const protocol::pb::ClientHello& hello) override;
    void on_input(Connection& session, const protocol::pb::ClientInput& input) override;
    void on_closed(Connection& session) override;
    /// Adds what `session` counted (bytes either way, snapshots dropped and paced, inputs
    /// dropped and clamped) to those totals of `stats`: a closed session's to stats_, the
    /// open ones' to a count of their own for /metrics.
    static void add_session_counts(const Connection& session, ServerStats& stats);
    /// A new connection (either transport): registered; a TCP one counts among those
    /// waiting for their hello (max_pending_per_source, max_pending_connections).
    void open_connection(const std::shared_ptr<Connection>& connection);
    /// A client id no open connection or client holds (client_ids.hpp).
    [[nodiscard]] std::uint32_t take_client_id();
    /// Client `id` no longer waits for its hello (it joined, or left): its place among
    /// the pending connections, if it held one, is free.
    void release_pending(std::uint32_t id);

    boost::asio::io_context& io_;
    IoLoop* io_loop_ = nullptr;
    ServerConfig config_;
    boost::asio::ip::tcp::acceptor acceptor_;
    std::unique_ptr<UdpEndpoint> udp_; // when config.udp, from start()
    boost::asio::steady_timer tick_timer_;
    std::chrono::nanoseconds tick_period_;
    TickSchedule schedule_; // when ticks are due; missed ones are dropped, not burst
    std::chrono::steady_clock::time_point last_skip_log_; // skips are logged every 10 s at most
    std::uint64_t skipped_since_log_ = 0;
    std::uint64_t tick_ = 0;
    interest::GameWorld world_;           // role gateway: a mirror of the world process's
    std::unique_ptr<WorldFeed> feed_;     // role gateway, from start()
    std::uint64_t tick_published_ns_ = 0; // role gateway: this tick's WorldTick::published_ns
    std::vector<scaleout::PlayerInput> outgoing_inputs_; // role gateway: this tick's inputs
    std::vector<std::uint32_t> outgoing_ids_;            // role gateway: joins or leaves
    std::unique_ptr<interest::InterestPolicy> policy_;
    std::map<std::uint32_t, Client> clients_; // active (after hello)
    // TCP connections waiting for their hello (max_pending_connections), and those of
    // each source, oldest first (max_pending_per_source).
    std::unordered_map<std::uint32_t, SourceKey> pending_;
    std::unordered_map<SourceKey, std::deque<std::uint32_t>, SourceKeyHash> pending_by_source_;
    std::map<std::uint32_t, std::shared_ptr<Connection>> sessions_; // all open connections
    std::uint32_t next_client_id_ = 1;
    std::unique_ptr<protocol::TokenKey> token_key_;        // null when insecure
    std::map<std::uint64_t, std::uint32_t> token_clients_; // token client id -> connection
    bool started_ = false;                                 // start() succeeded
    bool shutting_down_ = false;
    std::function<void()> on_shutdown_done_;
    ServerStats stats_;
    std::vector<std::uint32_t> pending_joins_;  // clients whose entity spawns next tick start
    std::vector<std::uint32_t> pending_leaves_; // closed clients to remove when no phase runs
    std::size_t tbvs_alive_ = 0;                // policy_->tbvs_alive() at the last hand-over
    // This tick, from its start to its hand-over. While phase_running_, the jobs own
    // world_, policy_, shared_poses_, client_ticks_ and what the jobs point to.
    bool phase_running_ = false;
    std::optional<boost::asio::executor_work_guard<boost::asio::io_context::executor_type>>
        phase_work_; // keeps io_context::run() going until the hand-over
    std::chrono::steady_clock::time_point tick_start_;
    std::chrono::steady_clock::time_point culling_start_;
    CullingBudget culling_budget_; ///< this tick's fail-open deadline (config culling_budget)
    std::vector<ClientTick> client_ticks_; // this tick's jobs, in client id order
    std::vector<Client*> tick_clients_;    // the client of each job (clients_ is a std::map)
    std::vector<Client*> direct_writes_;   // the hand-over's clients whose frame goes straight out
    std::vector<std::size_t> direct_written_; // bytes the kernel took of each of those frames
    SharedPoses shared_poses_;                // this tick's quantized poses, for every job
    interest::Hearing hearing_;               // this tick's sounds, for every job
    std::unique_ptr<trace::TraceWriter> trace_;
    trace::TraceTick trace_tick_;
    WorkerPool pool_; // last: its threads stop first (after ~Server waited for a phase)
};

} // namespace dsoc::server
