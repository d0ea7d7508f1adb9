#pragma once
// What one client knows, and how a new interest set becomes a compact snapshot of
// enter / update / leave (protocol version 3: quantized poses, updates as deltas
// against what this client last received, only changed fields present).
//
// Threading: one per client; build_snapshot() of distinct clients may run
// concurrently (it only reads the world).

#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/protocol/acked_snapshot.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/messages.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace dsoc::server {

/// The wire pose of a world entity.
[[nodiscard]] protocol::Pose pose_of(const interest::Entity& e);

/// Every entity's wire pose this tick, quantized on each network level-of-detail
/// tier (and the heard tier) once for all clients (instead of once per client that is sent it).
/// Threading: compute() serial; at() may be read concurrently afterwards.
class SharedPoses {
public:
    /// For every entity of `world` (in its order) and every tier of `quantization`.
    void compute(const interest::GameWorld& world,
                 const protocol::QuantizationSettings& quantization);
    /// The pose of world.entities()[index] on `tier`, as of the last compute().
    [[nodiscard]] const protocol::QuantizedPose& at(std::size_t index, std::uint8_t tier) const {
        return poses_[index * protocol::kTiers + tier];
    }
    [[nodiscard]] const protocol::QuantizationSettings& quantization() const {
        return quantization_;
    }
    [[nodiscard]] std::size_t size() const { return ids_.size(); }
    /// The ids of world.entities() side by side (increasing, as the world keeps them):
    /// what a snapshot walks to find its entities without touching each whole entity.
    [[nodiscard]] const std::vector<std::uint32_t>& ids() const { return ids_; }

private:
    protocol::QuantizationSettings quantization_;
    std::vector<protocol::QuantizedPose> poses_;
    std::vector<std::uint32_t> ids_;
};

class ReplicationState {
public:
    /// `quantization` must have passed protocol::validate(). `acked`: the client's
    /// transport loses snapshots and acknowledges the ones it applied (UDP): snapshots are
    /// built with build_acked_snapshot(), else with build_snapshot().
    explicit ReplicationState(const protocol::QuantizationSettings& quantization = {},
                              bool acked = false)
        : encoder_(quantization),
          acked_encoder_(acked ? std::make_unique<protocol::AckedSnapshotEncoder>(quantization)
                               : nullptr) {}

    [[nodiscard]] bool acked() const { return acked_encoder_ != nullptr; }

    /// Fills `snapshot` (cleared first) for `tick`: entities in `interest` (increasing
    /// ids, each present in `world`) that the client did not know enter with full
    /// state; known ones whose quantized state changed since last sent get an update
    /// holding the changed fields - except that an entity is updated only on ticks
    /// protocol::due_at() names for its tier (tiers 1 and 2 cost a half and a quarter of
    /// the updates; the heard tier as the far one); known ones not in `interest` leave. Afterwards
    /// the client knows exactly `interest`. `audit`: also fill snapshot.audit with the exact pose
    /// of every entity made current but those on the heard tier. `poses`
    /// (optional): this tick's SharedPoses of `world`, computed with this state's
    /// quantization; the bytes are the same with or without it. `columns` (optional):
    /// the update entries go there in wire form instead of into `snapshot` (frame both
    /// with protocol::encode_snapshot_frame(); the same bytes).
    void build_snapshot(const interest::GameWorld& world,
                        std::span<const interest::Interest> interest, std::uint64_t tick,
                        bool audit, protocol::pb::Snapshot& snapshot,
                        const SharedPoses* poses = nullptr,
                        protocol::UpdateColumns* columns = nullptr);

    /// The acknowledged-delta snapshot of `tick` (protocol/acked_snapshot.hpp) that moves
    /// the client to `interest`, coded against the frame of `acked_tick` (the newest tick
    /// the client acknowledged) when the encoder still holds it, else against nothing.
    /// Entities on tier t > 0 are updated when due (protocol::due_since(): the first
    /// snapshot after their staggered tick of the interval) and held on the others. `audit`: the
    /// exact pose of every tier-0 entity (those are updated every tick). `poses`, `columns`: as
    /// build_snapshot()'s (frame with snapshot_frame() given the same columns). Only when
    /// acked().
    /// At most protocol::kMaxEntersPerSnapshot entities enter: when more want to, those on
    /// the lowest tier (seen before heard) and, within a tier, nearest `eye` enter, and the
    /// rest are left for later snapshots (last_deferred()); the client then knows
    /// `interest` less those.
    /// The snapshot's envelope never takes more than protocol::kMaxSnapshotBytes (what its
    /// datagrams carry): when it would, every leave is written, and the enters and update
    /// entries that fit, in the same order (those deferred snapshots in a row
    /// kPromoteAfter times or more first, the longest waiting first), the rest deferred:
    /// an entity whose entry is left out stays known, as the client takes it from a
    /// snapshot without its entry (at its prediction, or held on a tick it is not due),
    /// and its next entry repairs it (last_updates_deferred()). Audit poses go in while
    /// there is room, never of an entity whose entry was left out. When the leaves alone
    /// do not fit, the snapshot is coded against nothing: it leaves nothing and enters
    /// what fits (the client forgets the rest, as any snapshot coded against nothing).
    void build_acked_snapshot(const interest::GameWorld& world,
                              std::span<const interest::Interest> interest, glm::vec3 eye,
                              std::uint64_t tick, std::optional<std::uint64_t> acked_tick,
                              bool audit, protocol::pb::Snapshot& snapshot,
                              const SharedPoses* poses = nullptr,
                              protocol::UpdateColumns* columns = nullptr);

    /// Enters and update entries the last snapshot built holds.
    [[nodiscard]] std::size_t last_updates() const { return last_updates_; }
    /// What the last build_acked_snapshot() coded against.
    [[nodiscard]] const protocol::AckedSnapshotCounts& last_acked() const { return last_acked_; }
    /// Entities of the last build_acked_snapshot()'s interest that did not enter for want of
    /// room (protocol::kMaxEntersPerSnapshot, or the datagrams' bytes).
    [[nodiscard]] std::size_t last_deferred() const { return last_deferred_; }
    /// Update entries of the last build_acked_snapshot() left out for want of room (bytes):
    /// those entities are known, at their prediction until a later entry.
    [[nodiscard]] std::size_t last_updates_deferred() const { return last_updates_deferred_; }
    /// An entity deferred this many snapshots in a row goes before every one deferred
    /// fewer times, whatever its distance or tier: under a load that never fits, each
    /// entity is still written within a few snapshots. [Units: snapshots]
    static constexpr std::uint16_t kPromoteAfter = 3;
    [[nodiscard]] std::size_t known_count() const { return known_.size(); }
    [[nodiscard]] const std::vector<std::uint32_t>& known() const { return known_; }

private:
    /// Fills enter_allowed_ (one flag per entry of `interest`) when more entities want to
    /// enter than a snapshot takes; leaves it empty (all may enter) otherwise.
    void choose_enters(const interest::GameWorld& world,
                       std::span<const interest::Interest> interest, glm::vec3 eye,
                       const protocol::DeltaFrame* baseline);
    /// build_acked_snapshot() for a snapshot that may not fit (replication_state.cpp).
    void build_measured(const interest::GameWorld& world,
                        std::span<const interest::Interest> interest, glm::vec3 eye, bool audit,
                        protocol::pb::Snapshot& snapshot, const SharedPoses* poses,
                        protocol::UpdateColumns* columns);

    protocol::SnapshotEncoder encoder_;
    std::unique_ptr<protocol::AckedSnapshotEncoder> acked_encoder_; // when acked()
    std::size_t last_updates_ = 0;
    protocol::AckedSnapshotCounts last_acked_;
    std::vector<std::uint32_t> known_; // increasing
    std::vector<std::uint32_t> next_known_;
    std::size_t last_deferred_ = 0;
    std::size_t last_updates_deferred_ = 0;
    /// The entities the last snapshot that did not fit left out (enters and entries), and
    /// those still waiting for the tick they are due, with how many snapshots in a row they
    /// were left out; increasing ids. Empty after a snapshot that fitted.
    struct Waiting {
        std::uint32_t id = 0;
        std::uint16_t snapshots = 0;
    };
    std::vector<Waiting> waiting_;
    /// The last snapshot did not fit as first written: the next is measured at once.
    bool measure_first_ = false;
    std::vector<std::uint8_t> enter_allowed_; ///< choose_enters()'s, by interest index
    struct EnterCandidate {
        std::uint8_t tier = 0;
        float distance2 = 0.0f;  ///< from the eye, squared [world units^2]
        std::uint32_t index = 0; ///< in the interest set
    };
    std::vector<EnterCandidate> candidates_; ///< choose_enters()'s scratch
};

} // namespace dsoc::server
