#pragma once
// What one simulated client session saw, for the report.

#include "dsoc/simclient/sample_histogram.hpp"

#include <cstdint>
#include <map>
#include <string>

namespace dsoc::simclient {

struct ClientStats {
    bool connect_failed = false; ///< resolving, connecting or the hello failed
    bool hello_received = false;
    bool saw_own_entity = false;
    bool unexpected_disconnect = false; ///< lost, or told to go for a reason other than shutdown
    std::string disconnect_reason;      ///< from the server's Disconnect, if any
    std::string disconnect_text;
    /// Why the session failed (failure_reason.hpp), "" when it did not; the first
    /// failure only. `failure_detail` says more ("connect to 127.0.0.1:1: Connection
    /// refused").
    std::string failure;
    std::string failure_detail;
    /// The session lost its server and another session of the same client took over at
    /// the next server (LoadConfig::more_servers): `failure` says why, but the report
    /// counts it as a failover, not as a failure or an unexpected disconnect.
    bool failed_over = false;
    std::uint32_t entity_id = 0;
    std::uint64_t bytes_down = 0; ///< frame headers included
    std::uint64_t bytes_up = 0;
    std::uint64_t snapshots = 0;
    std::uint64_t entity_updates = 0; ///< enters + updates received
    /// The session decodes and checks its snapshots (LoadConfig::check_every); a
    /// discarding one counts and acknowledges them, and samples no replica.
    bool checks_snapshots = true;
    std::uint64_t audited_poses = 0; ///< replica poses checked against the server's
    /// Largest audit error: distance of a replica pose from the server's, in quanta
    /// (positions) or angle steps; at most 0.5 when the deltas decode right.
    double max_audit_error = 0.0;
    double active_seconds = 0.0;   ///< from server hello to stop
    double connect_ms = 0.0;       ///< start (resolve) to server hello; 0 without a hello
    SampleHistogram known_samples; ///< entities known after each snapshot
    /// Of them, entities known only by hearing (the heard tier: a coarse position, no
    /// angles; the decoder rejects angles or an audit pose for one).
    SampleHistogram heard_samples;
    SampleHistogram interarrival_ms; ///< between snapshots as the client handled them
    /// Over UDP: between snapshots as they reached the client's socket (the kernel's
    /// receive timestamps, plus emulated latency): the server's and the network's timing
    /// without the load generator's own delay in getting to them.
    SampleHistogram socket_interarrival_ms;
    /// Over UDP: from a snapshot reaching the socket (plus emulated latency) to its
    /// handling: the load generator's own delay (a busy machine, too few threads).
    SampleHistogram handling_lag_ms;
    SampleHistogram rtt_ms;
    std::map<std::string, std::uint64_t> protocol_errors; ///< by kind
};

} // namespace dsoc::simclient
