#pragma once
// Every server setting, with its default, unit and valid range. The defaults of what
// the interest layer reads are written once, there: interest::PolicySettings,
// interest::WorldSettings and visibility::DSOCConfig.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/protocol/quantization.hpp"
#include "dsoc/visibility/dsoc_config.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::server {

/// The highest tick rate a server or world process runs at (ServerConfig::tick_rate).
/// [Units: Hz]
inline constexpr int kMaxTickRate = 240;

/// One [dsoc] entry (dsoc_settings.hpp): a visibility::DSOCConfig field by name, its
/// value as text, and where it was set ("server.toml:12:1", "--dsoc"), for messages.
struct DsocSetting {
    std::string key;
    std::string value;
    std::string origin;
    friend bool operator==(const DsocSetting&, const DsocSetting&) = default;
};

struct ServerConfig {
    /// What this process is (docs/scale-out.md): "single", the whole game in one
    /// process; "world", the authoritative world of a scaled-out game (no clients: it
    /// moves the entities and publishes each tick on NATS); "gateway", an interest
    /// gateway (clients, their interest and snapshots; the world mirrored from NATS).
    std::string role = "single";
    /// The NATS server(s) a world and its gateways meet at ("nats://host:port",
    /// comma-separated).
    std::string nats_url = "nats://127.0.0.1:4222";
    /// The world's name: its NATS subjects are dsoc.<world_name>.*.
    /// [Limit: 1..64 of letters, digits, '-' and '_']
    std::string world_name = "dsoc";
    /// Address to listen on. Loopback by default: expose deliberately.
    std::string bind_address = "127.0.0.1";
    /// TCP port, and UDP's with `udp`; 0 picks a free port (printed at start).
    /// [Limit: 0..65535]
    std::uint16_t port = 27960;
    /// Also serve clients over UDP (docs/protocol.md, "UDP transport"), on the same port
    /// number as TCP (the one bound, when `port` is 0).
    bool udp = true;
    /// A UDP client from which nothing arrived for this long is disconnected with
    /// timed_out. [Units: ms] [Limit: 500..60000]
    int udp_timeout_ms = 5000;
    /// UDP responses with a valid cookie (an address proven to be the sender's) one
    /// source address (an IPv4 address, or an IPv6 /64) may send per second, with a burst
    /// of one second's worth; beyond it they are dropped unanswered (rate_limited). One
    /// address can hold many honest clients (a NAT, a load generator): each sends one to
    /// connect, and again every 250 ms while it waits. [Units: 1/s] [Limit: 1..1000000]
    int udp_handshake_rate = 100;
    /// UDP requests the server answers with a challenge per second, from all sources
    /// together, with a burst of one second's worth; beyond it they are dropped unanswered
    /// (over_challenge_rate). A request proves nothing of its source address (it may be
    /// spoofed), so it spends no address's budget (a spoofer would lock that address
    /// out): this cap bounds the CPU the answers take, one HMAC and a 42-byte datagram
    /// each. [Units: 1/s] [Limit: 1..1000000]
    int udp_challenge_rate = 10000;
    /// /metrics also gives dsoc_heap_in_use_bytes and dsoc_heap_free_bytes on glibc's
    /// malloc (mallinfo2, heap_stats.hpp): a diagnosis of resident memory that grows, off
    /// by default because each scrape walks the allocator's free chunks under its locks.
    /// On jemalloc (dsoc-server's allocator where the build found it) they are always
    /// given: reading them costs nothing.
    bool heap_metrics = false;
    /// Simulation and snapshot rate. [Units: Hz] [Limit: 1..kMaxTickRate]
    int tick_rate = visibility::DSOCConfig{}.tick_rate;
    /// Wandering bots. [Limit: 0..100000]
    int bots = interest::WorldSettings{}.bots;
    /// Teams (0: none): bots and players are dealt into teams 1..teams; every policy
    /// sends a client its teammates whatever it sees (interest beyond sight).
    /// [Limit: 0..1000]
    int teams = interest::WorldSettings{}.teams;
    /// Footsteps (entities running on the ground) and shots (bots at random, players
    /// with ClientInput.fire): a client is sent what it hears but cannot see on the heard
    /// tier (a coarse position, no angles; interest/hearing.hpp), whatever the policy.
    bool sounds = sim::SoundSettings{}.enabled;
    /// How far footsteps are heard. [Units: world units] [Limit: 0..100000]
    float footstep_range = sim::SoundSettings{}.footstep_range;
    /// How far a shot is heard. [Units: world units] [Limit: 0..100000]
    float shot_range = sim::SoundSettings{}.shot_range;
    /// How often a bot fires, on average. [Units: 1/s] [Limit: 0..100]
    float bot_shots_per_second = sim::SoundSettings{}.bot_shots_per_second;
    /// Health a shot takes from the entity it hits, of sim::kMaxHealth (0: harmless);
    /// an entity with none left dies and respawns at a spawn point (sim/shots.hpp).
    /// [Units: health points] [Limit: 0..100]
    int shot_damage = sim::ShotSettings{}.damage;
    /// Map: a name looked up in OpenArena's .pk3 archives (and $DSOC_MAP_PATH), a path
    /// to a .bsp or text map, or "gen:city[:seed]" / "gen:rooms[:seed]".
    std::string map = "oa_dm4";
    /// Interest policy: "dsoc" (occlusion culling with temporal coherence, latency-safe;
    /// TBVs when [dsoc] tbvs_enabled), "occlusion" (the same culler, every entity tested
    /// every tick),
    /// "pvs" (the map's PVS from the eye's cluster, as the Quake 3 server does),
    /// "distance" (radius) or "broadcast" (everything). Read and printed by these names
    /// (interest::kPolicyNames).
    interest::PolicyKind policy = interest::PolicySettings{}.policy;
    /// TBV strategy of the dsoc policy when its TBVs are on ([dsoc] tbvs_enabled = true):
    /// "adaptive", "explicit" or "fuzzy" (not conservative: for evaluation only).
    std::string tbv_strategy = visibility::to_string(visibility::DSOCConfig{}.strategy);
    /// Stages of the occlusion culler: "shaft" (exact single-occluder test, no
    /// per-region build), "pyramid" (extended-projection z-pyramid) or "both"
    /// (interest::kCullerNames).
    interest::CullerKind culler = interest::PolicySettings{}.culler;
    /// Levels of portal tests in the culler's shaft stage (RegionCullerConfig::
    /// portal_depth): deeper sends fewer entities for several times the culling CPU,
    /// so the server defaults to 0 (capacity) where the library and the evaluation
    /// default to 2 (docs/operations.md has the figures). [Limit: 0..4]
    int portal_depth = interest::PolicySettings{}.portal_depth;
    /// dsoc and occlusion: reject first what the map's PVS (Quake 3 maps with vis data)
    /// proves hidden from every cluster of the client's eye region.
    bool pvs_stage = interest::PolicySettings{}.pvs_stage;
    /// dsoc and occlusion: the map's baked cell visibility table first
    /// (docs/baked-visibility.md), loaded from the cache or baked at start (with
    /// progress on stderr; about a minute for oa_dm4 on two cores, once per map and
    /// cell size: `dsoc-bake MAP` does it ahead).
    bool baked_stage = interest::PolicySettings{}.baked_stage;
    /// Cell edge of the baked table. [Units: world units] [Limit: 4..1024]
    float bake_cell_size = interest::PolicySettings{}.bake_cell_size;
    /// Where baked tables are kept; empty: $DSOC_BAKE_DIR, $XDG_CACHE_HOME/dsoc/bakes or
    /// ~/.cache/dsoc/bakes.
    std::string bake_dir;
    /// With baked_stage: whether the PVS and shaft stages follow the table. "false": the
    /// table alone, the cheapest conservative answer; "true": the exact stages on what
    /// the table passes (tighter, dearer); "auto": the table alone when its cells are as
    /// fine as bake_cell_size, the exact stages too when the map needed coarser cells to
    /// fit the table's memory budget (open and large maps, where a coarse table hides
    /// little). Without baked_stage the exact stages always run. See docs/operations.md.
    /// (interest::kExactStagesNames).
    interest::ExactStages exact_stages = interest::PolicySettings{}.exact_stages;
    /// Fail-open: clients whose culling has not started this share of the tick period
    /// after the tick began get the policy's cheapest conservative answer (the baked
    /// table or the PVS alone, no exact stage) instead of making the tick late; counted
    /// in dsoc_culling_cheapest_client_ticks_total. 0: off. [Limit: 0..1]
    double culling_budget = 0.5;
    /// The dsoc policy reuses a client's culler region while the client's reachable
    /// eye region stays inside it grown by this margin: larger margins re-test hidden
    /// entities' TBVs less often but cull less. [Units: world units] [Limit: 0..512]
    float region_reuse_margin = visibility::DSOCConfig{}.region_reuse_margin;
    /// Time the server must cover a client's own movement for: round trip plus the
    /// client's interpolation delay. Rounded up to whole ticks. [Units: ms] [Limit: 0..2000]
    int latency_allowance_ms = 150;
    /// Write a replication trace (docs/replication-trace.md) to this file; empty: none.
    std::string trace_file;
    /// Record every k-th tick in the trace. [Limit: >= 1]
    int trace_every = 1;
    /// Radius of the distance policy, from the viewer's eye. [Units: world units] [Limit: > 0]
    float distance_radius = interest::PolicySettings{}.distance_radius;
    /// Worker threads for the per-client work of a tick (interest evaluation and
    /// snapshot building); 0: one per core. The I/O thread is not one of them: it keeps
    /// serving sockets while they work. Results do not depend on it. [Limit: 0..256]
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
    /// Position quantum of entities a client hears but does not see (no angles either).
    /// [Units: world units] [Limit: position_quantum_far..1024]
    float heard_quantum = protocol::QuantizationSettings{}.heard_quantum;
    /// false: every entity near (every tick, finest quantum), whatever the policy says.
    bool network_lod = true;
    /// Connected clients at most; a hello beyond them is refused with `server_full`.
    /// Connections that have not said their hello yet do not count. [Limit: 1..100000]
    int max_clients = 256;
    /// TCP connections waiting for their hello at most, from all sources together: a new
    /// one beyond them closes the oldest waiting connection of the source holding the
    /// most (with `try_again`). Bounds what silent connections hold (each until
    /// handshake_timeout_ms), and a newcomer, who says its hello at once, still gets in.
    /// [Limit: 1..1000000]
    int max_pending_connections = 1024;
    /// TCP connections waiting for their hello from one source (an IPv4 address, or an IPv6
    /// /64) before a new one from it must say its hello within kCrowdedHelloMs (instead of
    /// handshake_timeout_ms) or be closed with handshake_timeout: one host's silent
    /// connections then hold few of the max_pending_connections places, while a load
    /// generator connecting hundreds of clients at once from one address, each saying its
    /// hello at once, is not refused. [Limit: 1..1000000]
    int max_pending_per_source = 64;
    /// The hello deadline of a connection from a source with max_pending_per_source
    /// connections waiting. [Units: ms]
    static constexpr int kCrowdedHelloMs = 500;
    /// Largest frame payload a client may send. [Units: bytes] [Limit: 64..16 MiB]
    std::uint32_t max_frame_bytes = 64 * 1024;
    /// A client's queued, unsent bytes (its one pending snapshot plus replies) at most
    /// before it is disconnected as too slow. [Units: bytes] [Limit: >= max_frame_bytes]
    std::size_t max_send_queue_bytes = 1024 * 1024;
    /// A connection that has not said a valid hello by then is closed. [Units: ms] [Limit: > 0]
    int handshake_timeout_ms = 5000;
    /// A client with a snapshot still unsent after this long is disconnected as too slow.
    /// Until then the snapshots it cannot take are dropped (latest wins: the next one it
    /// gets is built from the newest state). [Units: ms] [Limit: 100..60000]
    int slow_client_timeout_ms = 3000;
    /// Kernel send buffer of each client socket (SO_SNDBUF); 0 keeps the OS default
    /// (Linux autotunes it up to net.ipv4.tcp_wmem's maximum, several MiB per client).
    /// [Units: bytes] [Limit: 0 or 4096..16 MiB]
    int socket_send_buffer_bytes = 0;
    /// How long the I/O thread lets socket events gather after each wakeup before it
    /// waits for them again; what may be late by this much is in io_loop.hpp. 0: it
    /// wakes for each arrival. [Units: µs] [Limit: 0..20000, and at most a quarter of
    /// the tick period]
    int io_gather_us = 1000;
    /// Messages (inputs and pings) a client may send per second; a burst of one
    /// second's worth is allowed. Beyond it messages are dropped, and a client whose
    /// dropped messages within one second exceed this cap again is disconnected with
    /// input_flood. [Units: 1/s] [Limit: tick_rate + 2..10000]
    int max_inputs_per_second = 120;
    /// Accept clients without a connect token. For local tests and demos only.
    bool insecure = false;
    /// File holding the connect-token key: 64 hex digits (32 bytes), whitespace
    /// ignored. Required unless `insecure`. See docs/operations.md and dsoc-token.
    std::string token_key_file;
    /// Serve Prometheus metrics on http://metrics_bind_address:metrics_port/metrics.
    /// -1: no metrics endpoint; 0: any free port (printed at start). [Limit: -1..65535]
    int metrics_port = -1;
    /// Address of the metrics endpoint. Loopback by default: expose deliberately.
    std::string metrics_bind_address = "127.0.0.1";
    /// Log level: trace, debug, info, warn, error, critical or off.
    std::string log_level = "info";
    /// Log format on stderr: "text" for people, "json" for log collectors (one object a
    /// line: time, level, logger, msg; see logging.hpp).
    std::string log_format = "text";
    /// Horizontal speed bound of every entity, enforced by the server. [Units: units/s] [Limit: >
    /// 0]
    float max_speed = interest::WorldSettings{}.max_speed;
    /// Seed for bots and spawn positions; the same seed gives the same bot motion.
    std::uint64_t seed = interest::WorldSettings{}.seed;
    /// Stop by itself after this long; 0 runs until SIGINT/SIGTERM. [Units: s] [Limit: >= 0]
    double duration_s = 0.0;
    /// The [dsoc] table: visibility::DSOCConfig fields set by name (each at most once, in
    /// the order set), applied over the flat keys and the policy's presets; see
    /// dsoc_settings.hpp. Each value is checked by DSOCConfig's validate(). Empty: none.
    std::vector<DsocSetting> dsoc;
};

/// Every problem with the settings, each naming the field and why; empty when usable.
std::vector<std::string> validate(const ServerConfig& config);

/// The snapshot quantization the settings describe.
[[nodiscard]] protocol::QuantizationSettings quantization(const ServerConfig& config);

/// The latency allowance in ticks (rounded up).
[[nodiscard]] int lookahead_ticks(const ServerConfig& config);

} // namespace dsoc::server
