#pragma once

#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/simclient/scenario.hpp"
#include "dsoc/simclient/threshold.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace dsoc::simclient {

/// Settings of one load run. Without a scenario, `clients`, `duration_s` and
/// `ramp_up_s` make one (implicit_scenario).
struct LoadConfig {
    std::string host = "127.0.0.1";
    std::uint16_t port = 27960;
    /// More servers of the same game beside host:port, e.g. the interest gateways of
    /// one scaled-out world (docs/scale-out.md). Client i starts at server i modulo
    /// their count (host:port first); a session that loses its server (refused, timed
    /// out, connection lost or shut down before the run's end) is replaced at once by
    /// one of the same client at the next server: a failover, counted, not a failure.
    std::vector<std::pair<std::string, std::uint16_t>> more_servers;
    /// Simulated clients. [Limit: 1..100000]
    int clients = 32;
    /// Whole run, ramp-up included. [Units: s] [Limit: > 0]
    double duration_s = 15.0;
    /// Clients connect evenly spread over this time. [Units: s] [Limit: 0..duration_s]
    double ramp_up_s = 1.0;
    /// Largest frame accepted from the server. [Units: bytes]
    std::uint32_t max_frame_bytes = 16 * 1024 * 1024;
    /// Seed of the wandering intents.
    std::uint64_t seed = 7;
    /// One progress line per second on stderr.
    bool progress = true;
    /// Ask the server for its exact poses every this many ticks and check the decoded
    /// replica against them (within half a quantum); 0: never. Audits cost bytes
    /// (counted by both sides like any other). [Units: ticks]
    std::uint32_t audit_every_ticks = 30;
    /// One client in this many (load_run.hpp's picked_to_check(), and each group's first
    /// client on each thread) decodes each snapshot into a replica and checks it: the protocol's
    /// invariants, the audits, heard-only precision, the entity samples. The others
    /// read each snapshot's tick, acknowledge it and discard the rest, as a web load
    /// generator discards response bodies: the server codes and sends the same bytes to
    /// both, and the load generator spends a fraction of the CPU on a discarding client,
    /// so a run of many clients on the server's own machine takes less of its cores.
    /// Spectators always decode (they pick whom to watch from what they know), but sample
    /// only when picked. 1: every client checks. [Limit: >= 1]
    std::uint32_t check_every = 1;
    /// Prefix of the client names ("sim-0", "sim-1", ...).
    std::string name_prefix = "sim-";
    /// With a key (a load test that knows the server's secret), client i mints its own
    /// connect token for client id client_id_base + i, valid for token_ttl_s from its
    /// connect. Without one, every client sends `connect_token` (empty for servers
    /// started with --insecure).
    std::optional<protocol::TokenKey> token_key;
    std::uint64_t client_id_base = 1;
    /// [Units: s] [Limit: >= 1]
    std::uint64_t token_ttl_s = 60;
    std::vector<std::uint8_t> connect_token;
    /// Stages, groups and thresholds; when set, `clients`, `duration_s` and `ramp_up_s`
    /// are not used.
    std::optional<Scenario> scenario;
    /// More thresholds (the command line's), checked with the scenario's.
    std::vector<Threshold> thresholds;
    /// Resolve, TCP connect and server hello must finish within this; when set, it
    /// overrides the scenario's connect_timeout. [Units: s] [Limit: > 0]
    std::optional<double> connect_timeout_s;
    /// The protocol version sent in the hello. A testing aid: a server refuses any
    /// other than its own (version_mismatch).
    std::uint32_t protocol_version = protocol::kProtocolVersion;
    /// How the clients reach the server: UDP datagrams with acknowledged-delta snapshots
    /// (docs/protocol.md, "UDP transport"; what a game's clients use), or a TCP stream of
    /// compact snapshots.
    enum class Transport : std::uint8_t { tcp, udp };
    Transport transport = Transport::udp;
    /// UDP only: datagram faults for every client (emulated loss, duplication and
    /// reordering, on top of the groups' latency and jitter); a group's own faults
    /// (scenario files) count where larger.
    DatagramFaults udp_faults;
};

} // namespace dsoc::simclient
