#pragma once
// A load run: N simulated clients on one io_context, ramped up, run for a fixed
// time, stopped cleanly, then summarized.

#include "dsoc/common/percentiles.hpp"
#include "dsoc/simclient/load_config.hpp"
#include "dsoc/simclient/sim_client.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dsoc::simclient {

struct LoadReport {
    LoadConfig config;
    double wall_seconds = 0.0;
    int clients = 0;
    int connected = 0;        ///< got a server hello
    int connect_failures = 0; ///< TCP connect failed, or no hello arrived
    int unexpected_disconnects = 0;
    int missing_own_entity = 0; ///< connected clients that never saw their own entity
    std::uint64_t protocol_errors = 0;
    std::map<std::string, std::uint64_t> protocol_errors_by_kind;
    std::map<std::string, std::uint64_t> disconnect_reasons;
    std::uint64_t bytes_down = 0;
    std::uint64_t bytes_up = 0;
    std::uint64_t snapshots = 0;
    std::uint64_t entity_updates = 0;
    std::uint64_t audited_poses = 0;      ///< replica poses checked against the server's exact ones
    double max_audit_error = 0.0;         ///< [Units: quanta or angle steps] <= 0.5 when correct
    double bytes_down_per_client_s = 0.0; ///< mean over connected clients of bytes / active s
    double bytes_up_per_client_s = 0.0;
    double entity_updates_per_client_s = 0.0;
    common::Summary entities_known; ///< over every snapshot of every client
    common::Summary snapshot_interarrival_ms;
    common::Summary rtt_ms;

    /// A load test gates on this: every client connected, no protocol error, no
    /// unexpected disconnect, every client saw its own entity.
    [[nodiscard]] bool passed() const {
        return connect_failures == 0 && protocol_errors == 0 && unexpected_disconnects == 0 &&
               missing_own_entity == 0 && connected == clients;
    }
};

class LoadRun {
public:
    LoadRun(boost::asio::io_context& io, LoadConfig config);

    /// Schedules everything; io_context::run() returns when the run is over.
    void start();
    /// Ends the run early (e.g. on SIGINT): stops every client now.
    void stop();

    [[nodiscard]] LoadReport report() const;
    [[nodiscard]] const std::vector<std::shared_ptr<SimClient>>& clients() const {
        return clients_;
    }

private:
    void connect_next();
    void print_progress();

    boost::asio::io_context& io_;
    LoadConfig config_;
    std::vector<std::shared_ptr<SimClient>> clients_;
    boost::asio::steady_timer ramp_timer_;
    boost::asio::steady_timer progress_timer_;
    boost::asio::steady_timer end_timer_;
    std::chrono::steady_clock::time_point started_;
    std::chrono::steady_clock::time_point stopped_;
    std::size_t next_to_connect_ = 0;
    bool stopping_ = false;
    std::uint64_t last_bytes_down_ = 0;
    std::uint64_t last_bytes_up_ = 0;
    std::uint64_t last_snapshots_ = 0;
};

/// Readable multi-line summary.
std::string format_summary(const LoadReport& report);
/// The report as JSON (see docs/simclient.md for the keys).
std::string format_json(const LoadReport& report);

} // namespace dsoc::simclient
