#pragma once
// The per-client half of a server tick: each client's interest set (the policy's
// select(), which for dsoc/occlusion is that client's occlusion culling) and its
// compact snapshot, run for all clients on a WorkerPool. What each client receives
// depends only on the world, the tick and that client's own history, so the bytes
// are identical whatever the thread count (tests/server/parallel_tick_test.cpp).

#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/hearing.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/protocol/update_columns.hpp"
#include "dsoc/server/replication_state.hpp"
#include "dsoc/server/worker_pool.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <span>
#include <vector>

namespace dsoc::server {

/// One client's work this tick. The pointed-to objects belong to the client (one
/// set per client, never shared), so distinct jobs touch distinct state.
struct ClientTick {
    interest::Viewer viewer;
    ReplicationState* replication = nullptr;
    std::vector<interest::Interest>* interest = nullptr; ///< receives the interest set
    protocol::pb::Envelope* envelope = nullptr;          ///< receives the snapshot when `build`
    /// When not null and `build`: receives the snapshot encoded as one wire frame
    /// (cleared first; its capacity is reused), so serialization runs on the pool too: a
    /// TCP frame, or when replication->acked() the form snapshot_frame() gives (what a
    /// UdpConnection takes).
    std::vector<std::uint8_t>* frame = nullptr;
    /// When replication->acked(): the newest snapshot tick the client acknowledged.
    std::optional<std::uint64_t> acked_tick;
    /// Optional, with `frame`: the snapshot's update entries are written here in wire
    /// form and framed with them (protocol::encode_snapshot_frame(), or snapshot_frame()
    /// when acked: the same bytes, without a second pass over them); `envelope`'s
    /// snapshot then holds no update entries.
    protocol::UpdateColumns* columns = nullptr;
    /// Optional: this tick's poses quantized once for all clients (same bytes).
    const SharedPoses* poses = nullptr;
    /// false: select() still runs (the culler keeps its per-tick state) but no
    /// snapshot is built - the client could not take one (latest wins), and its
    /// replica stays what was really sent.
    bool build = true;
    bool audit = false;      ///< fill Snapshot.audit with the exact poses
    bool network_lod = true; ///< false: every entity seen on tier 0
    /// Optional: this tick's sounds; what the viewer hears and the policy did not send
    /// is added on the heard tier (interest::Hearing::add_heard).
    const interest::Hearing* hearing = nullptr;
    /// Optional: receives how many entities hearing added (0 without `hearing`).
    std::uint32_t* heard = nullptr;
};

/// Fail-open for one tick's parallel phase: a job whose turn comes after `deadline` gets
/// the policy's select_cheapest() instead of select() (still conservative, far cheaper),
/// and is counted in `cheapest`. The jobs start in an order that moves every tick, so
/// the late turns fall on different clients. Without a deadline the bytes do not
/// depend on timing.
struct CullingBudget {
    bool enabled = false;
    std::chrono::steady_clock::time_point deadline;
    std::atomic<std::uint64_t> cheapest{0}; ///< jobs given the cheapest answer
};

/// Adds the viewer's own entity `entity_id` to `interest` (increasing ids) on tier 0: a
/// client always gets its own entity every tick, finest, whatever the policy said.
void add_own_entity(std::vector<interest::Interest>& interest, std::uint32_t entity_id);

/// For every job: policy.select() (plus the viewer's own entity), then, when
/// `build`, the snapshot of `tick` (and its frame when `frame` is set). policy.begin_tick(world,
/// tick) must have run; `world` and the policy's shared state are only read meanwhile.
/// `budget` (may be null: no deadline) must outlive the call.
void run_client_ticks(const interest::GameWorld& world, interest::InterestPolicy& policy,
                      std::uint64_t tick, std::span<const ClientTick> jobs, WorkerPool& pool,
                      CullingBudget* budget = nullptr);

/// The same jobs, on the pool's own threads (WorkerPool::start): returns at once, and
/// `done(error)` runs on a pool thread once every job has returned (error: the first
/// exception a job threw, or null). Until then the jobs own `world`, `policy`, the
/// span's memory and everything the jobs point to: the caller must neither write nor
/// destroy any of it (reading `world` is fine), and must keep all of it alive (`budget`
/// too, when not null). The bytes are the same as run_client_ticks() gives.
void start_client_ticks(const interest::GameWorld& world, interest::InterestPolicy& policy,
                        std::uint64_t tick, std::span<const ClientTick> jobs, WorkerPool& pool,
                        std::function<void(std::exception_ptr)> done,
                        CullingBudget* budget = nullptr);

} // namespace dsoc::server
