#pragma once
// The dsoc game server: accepts clients, runs a fixed-rate tick loop, moves every
// entity authoritatively and sends each client the snapshot its interest policy
// allows. Threading: sockets, sessions and the world live on the io_context given to
// it (run it on one thread). Each tick, the per-client work - interest evaluation
// and snapshot building - runs on a WorkerPool of config.threads threads (the
// io_context thread among them), so no I/O is served while that part runs;
// snapshots go to the sockets afterwards, on the io_context thread.

#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/client_tick.hpp"
#include "dsoc/server/connect_token.hpp"
#include "dsoc/server/game_world.hpp"
#include "dsoc/server/interest_policy.hpp"
#include "dsoc/server/metrics.hpp"
#include "dsoc/server/replication_state.hpp"
#include "dsoc/server/server_config.hpp"
#include "dsoc/server/session.hpp"
#include "dsoc/server/tick_schedule.hpp"
#include "dsoc/trace/trace_writer.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
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
    std::uint64_t clients_accepted = 0;
    std::map<std::string, std::uint64_t> disconnects; ///< by reason name
    // Of closed connections (render_metrics() adds the live ones).
    std::uint64_t snapshots_dropped = 0; ///< not built: the client's previous one was unsent
    std::uint64_t inputs_dropped = 0;    ///< client messages over max_inputs_per_second
    std::uint64_t inputs_clamped = 0;    ///< inputs with an out-of-range field clamped
    std::size_t peak_queued_bytes = 0;   ///< largest send queue of any client
    std::vector<double> tick_cost_us;    ///< per tick, work time (not waiting), microseconds
    DurationHistogram tick_duration;     ///< the same work time, for /metrics
    /// Per tick, wall time of the policy's begin_tick and the per-client work on the
    /// pool: interest evaluation (culling) and snapshot building of every client.
    DurationHistogram culling_duration;
};

class Server final : private SessionHost {
public:
    /// `config` must have passed validate(); `map` is the loaded config.map.
    Server(boost::asio::io_context& io, ServerConfig config, std::shared_ptr<const maps::Map> map);
    ~Server() override;
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    /// Binds, listens and starts the tick loop. Returns the bound port (useful with
    /// port 0). Throws boost::system::system_error when the address cannot be bound,
    /// std::runtime_error when the trace file or the token key cannot be read.
    std::uint16_t start();

    /// Stops accepting, stops ticking, tells every client `server_shutdown`, and lets
    /// the connections drain; io_context::run() then returns once all are closed.
    /// `on_done` (optional) runs when the last connection has closed.
    void shutdown(std::function<void()> on_done = {});

    [[nodiscard]] const ServerStats& stats() const { return stats_; }
    [[nodiscard]] const ServerConfig& config() const { return config_; }
    [[nodiscard]] std::size_t session_count() const { return sessions_.size(); }
    [[nodiscard]] std::uint64_t tick() const { return tick_; }
    /// Everything an operator watches, in the Prometheus text format (what /metrics
    /// serves; the names are listed in docs/operations.md). Totals include the live
    /// connections. Call on the io_context thread.
    [[nodiscard]] std::string render_metrics() const;

private:
    struct Client {
        std::shared_ptr<Session> session;
        ReplicationState replication;
        std::vector<Interest> interest;  // this tick's set, written by the worker pool
        protocol::pb::Envelope envelope; // this tick's snapshot, written by the worker pool
        std::uint32_t audit_every = 0;   // ClientHello.audit_every_ticks
        std::vector<std::uint8_t> frame; // this tick's snapshot frame, written by the pool
    };

    void accept_next();
    void schedule_tick();
    void run_tick();
    void prepare_client_ticks();
    void send_snapshots();
    void maybe_finish_shutdown();
    void write_trace_tick();

    void on_hello(Session& session, const protocol::pb::ClientHello& hello) override;
    void on_input(Session& session, const protocol::pb::ClientInput& input) override;
    void on_closed(Session& session) override;

    boost::asio::io_context& io_;
    ServerConfig config_;
    boost::asio::ip::tcp::acceptor acceptor_;
    boost::asio::steady_timer tick_timer_;
    std::chrono::nanoseconds tick_period_;
    TickSchedule schedule_; // when ticks are due; missed ones are dropped, not burst
    std::chrono::steady_clock::time_point last_skip_log_; // skips are logged every 10 s at most
    std::uint64_t skipped_since_log_ = 0;
    std::uint64_t tick_ = 0;
    GameWorld world_;
    std::unique_ptr<InterestPolicy> policy_;
    std::map<std::uint32_t, Client> clients_;                    // active (after hello)
    std::map<std::uint32_t, std::shared_ptr<Session>> sessions_; // all open connections
    std::uint32_t next_client_id_ = 1;
    std::unique_ptr<TokenKey> token_key_;                  // null when insecure
    std::map<std::uint64_t, std::uint32_t> token_clients_; // token client id -> connection
    bool shutting_down_ = false;
    std::function<void()> on_shutdown_done_;
    ServerStats stats_;
    WorkerPool pool_;
    std::vector<ClientTick> client_ticks_; // this tick's jobs, in client id order
    std::vector<Client*> tick_clients_;    // the client of each job (clients_ is a std::map)
    SharedPoses shared_poses_;             // this tick's quantized poses, for every job
    std::unique_ptr<trace::TraceWriter> trace_;
    trace::TraceTick trace_tick_;
};

} // namespace dsoc::server
