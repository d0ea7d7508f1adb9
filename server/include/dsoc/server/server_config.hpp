#pragma once
// Every server setting, with its default, unit and valid range.

#include "dsoc/protocol/quantization.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::server {

struct ServerConfig {
    /// Address to listen on. Loopback by default: expose deliberately.
    std::string bind_address = "127.0.0.1";
    /// TCP port; 0 picks a free port (printed at start). [Limit: 0..65535]
    std::uint16_t port = 27960;
    /// Simulation and snapshot rate. [Units: Hz] [Limit: 1..240]
    int tick_rate = 30;
    /// Wandering bots. [Limit: 0..100000]
    int bots = 200;
    /// Map: a name looked up in OpenArena's .pk3 archives (and $DSOC_MAP_PATH), a path
    /// to a .bsp or text map, or "gen:city[:seed]" / "gen:rooms[:seed]".
    std::string map = "oa_dm4";
    /// Interest policy: "dsoc" (occlusion culling with TBVs, latency-safe),
    /// "occlusion" (the same culler, every entity tested every tick, no TBVs),
    /// "pvs" (the map's PVS from the eye's cluster, as the Quake 3 server does),
    /// "distance" (radius) or "broadcast" (everything).
    std::string policy = "dsoc";
    /// TBV strategy of the dsoc policy: "adaptive", "explicit" or "fuzzy" (not
    /// conservative: for evaluation only).
    std::string tbv_strategy = "adaptive";
    /// Stages of the occlusion culler: "shaft" (exact single-occluder test, no
    /// per-region build), "pyramid" (extended-projection z-pyramid) or "both".
    std::string culler = "shaft";
    /// dsoc and occlusion: reject first what the map's PVS (Quake 3 maps with vis data)
    /// proves hidden from every cluster of the client's eye region.
    bool pvs_stage = true;
    /// The dsoc policy reuses a client's culler region while the client's reachable
    /// eye region stays inside it grown by this margin: larger margins re-test hidden
    /// entities' TBVs less often but cull less. [Units: world units] [Limit: 0..512]
    float region_reuse_margin = 16.0f;
    /// Time the server must cover a client's own movement for: round trip plus the
    /// client's interpolation delay. Rounded up to whole ticks. [Units: ms] [Limit: 0..2000]
    int latency_allowance_ms = 150;
    /// Write a replication trace (shared/specs/replication-trace.md) to this file; empty: none.
    std::string trace_file;
    /// Record every k-th tick in the trace. [Limit: >= 1]
    int trace_every = 1;
    /// Radius of the distance policy, from the viewer's eye. [Units: world units] [Limit: > 0]
    float distance_radius = 1500.0f;
    /// Threads for the per-client work of a tick (interest evaluation and snapshot
    /// building), the tick thread included; 0: one per core. Results do not depend on
    /// it. [Limit: 0..256]
    int threads = 0;
    /// Position quantum of compact snapshots per network level-of-detail tier: near
    /// (updated every tick), mid (every 2nd) and far (every 4th); the dsoc and
    /// occlusion policies pick the tier from the client-entity distance, the others
    /// send everything near. [Units: world units] [Limit: 1/1024..64, near <= mid <= far]
    float position_quantum_near = 0.125f;
    float position_quantum_mid = 0.5f;
    float position_quantum_far = 1.0f;
    /// Steps per full turn of the angles in snapshots. [Limit: 256..65536]
    std::uint32_t angle_steps = 4096;
    /// false: every entity near (every tick, finest quantum), whatever the policy says.
    bool network_lod = true;
    /// Connected clients at most; more are refused with `server_full`. [Limit: 1..100000]
    int max_clients = 256;
    /// Largest frame payload a client may send. [Units: bytes] [Limit: 64..16 MiB]
    std::uint32_t max_frame_bytes = 64 * 1024;
    /// A client's queued, unsent snapshot bytes at most before it is disconnected as
    /// too slow. [Units: bytes] [Limit: >= max_frame_bytes]
    std::size_t max_send_queue_bytes = 1024 * 1024;
    /// A connection that has not said a valid hello by then is closed. [Units: ms] [Limit: > 0]
    int handshake_timeout_ms = 5000;
    /// Horizontal speed bound of every entity, enforced by the server. [Units: units/s] [Limit: >
    /// 0]
    float max_speed = 320.0f;
    /// Seed for bots and spawn positions; the same seed gives the same bot motion.
    std::uint64_t seed = 1;
    /// Stop by itself after this long; 0 runs until SIGINT/SIGTERM. [Units: s] [Limit: >= 0]
    double duration_s = 0.0;
};

/// Every problem with the settings, each naming the field and why; empty when usable.
std::vector<std::string> validate(const ServerConfig& config);

/// The snapshot quantization the settings describe.
[[nodiscard]] protocol::QuantizationSettings quantization(const ServerConfig& config);

/// The latency allowance in ticks (rounded up).
[[nodiscard]] int lookahead_ticks(const ServerConfig& config);

} // namespace dsoc::server
