#pragma once
// Compact snapshots (protocol version 3, docs/protocol.md): the sender's and the
// receiver's halves of one connection's entity replica. The encoder remembers the
// quantized pose it last sent for every entity the connection knows and writes only
// the fields whose quantized value changed, as deltas; the decoder rebuilds the same
// integers and so the same poses, within half a quantum of the sender's state.
// Deltas are against what was last *sent*, which over TCP (reliable, ordered) is what
// the peer last received; an unreliable transport would need acknowledged baselines.
//
// Threading: neither class is thread-safe; one per connection. Distinct instances
// may be used concurrently (the server builds snapshots of many clients in parallel).

#include "dsoc/protocol/flat_id_map.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/protocol/quantization.hpp"
#include "dsoc/protocol/update_columns.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::protocol {

class SnapshotEncoder {
public:
    /// `settings` must have passed validate().
    explicit SnapshotEncoder(const QuantizationSettings& settings) : settings_(settings) {}

    /// Clears `out` and starts the snapshot of `tick`. `columns` (optional; cleared
    /// here): until the next begin(), update entries go there in wire form rather than
    /// into `out`'s repeated fields (frame the two with encode_snapshot_frame()).
    void begin(std::uint64_t tick, pb::Snapshot& out, UpdateColumns* columns = nullptr);
    /// `id` (unknown to the connection) enters with its full state on `tier`
    /// (< kTiers; kHeardTier: position at the heard quantum, no angles). `half_extents`
    /// in world units.
    void enter(std::uint32_t id, const Pose& pose, const std::array<float, 3>& half_extents,
               std::uint32_t kind, std::uint8_t tier, pb::Snapshot& out);
    /// `id` (known) is now at `pose` on `tier`: appends an update entry holding the
    /// fields whose quantized value changed, or nothing when none did. Within one
    /// snapshot, update() ids must increase. Returns the entry's UpdateField mask (0:
    /// no entry).
    std::uint32_t update(std::uint32_t id, const Pose& pose, std::uint8_t tier, pb::Snapshot& out);
    /// The same with the pose already quantized on `tier` (quantize(pose, settings(),
    /// tier)): a server quantizes
    /// each entity once per tick for all its clients. Same bytes as update(pose).
    std::uint32_t update_quantized(std::uint32_t id, const QuantizedPose& quantized,
                                   std::uint8_t tier, pb::Snapshot& out);
    /// `id` (known) leaves; the connection forgets it.
    void leave(std::uint32_t id, pb::Snapshot& out);

    /// A hint that update(id) comes soon (see FlatIdMap::prefetch).
    void prefetch(std::uint32_t id) const { baseline_.prefetch(id); }

    [[nodiscard]] bool knows(std::uint32_t id) const { return baseline_.contains(id); }
    [[nodiscard]] std::size_t known_count() const { return baseline_.size(); }
    [[nodiscard]] const QuantizationSettings& settings() const { return settings_; }

private:
    struct Baseline {
        QuantizedPose pose;
        std::uint8_t tier = 0;
    };
    QuantizationSettings settings_;
    FlatIdMap<Baseline> baseline_;
    UpdateColumns* columns_ = nullptr; ///< this snapshot's, or null: into its repeated fields
    std::uint32_t last_update_id_ = 0;
    bool any_update_ = false;
};

/// Something wrong with a received snapshot. `kind` is a stable snake_case name
/// (duplicate_enter, update_for_unknown_entity, leave_for_unknown_entity, bad_tier,
/// malformed_update, angles_on_heard_tier, audit_for_unknown_entity,
/// audit_of_heard_entity, pose_beyond_quantization); `detail`
/// says which entity and why.
struct SnapshotProblem {
    std::string kind;
    std::string detail;
};

/// One replicated entity as the receiver knows it. The fields every update touches
/// come first and the two one-byte fields sit together: 40 bytes, so that a replica
/// slot (FlatIdMap: id and flag, then this) is 48 bytes and spans fewer cache lines.
struct ReplicaEntity {
    QuantizedPose quantized;
    std::uint8_t tier = 0;
    std::uint8_t enter_tier = 0; ///< the tier it entered on
    std::uint32_t kind = 0;
    std::array<std::uint32_t, 3> half_extents{}; ///< in quanta of `enter_tier`
};
static_assert(sizeof(ReplicaEntity) == 40);

class SnapshotDecoder {
public:
    /// `settings`: the server's, from its ServerHello (from_message()).
    explicit SnapshotDecoder(const QuantizationSettings& settings = {}) : settings_(settings) {}
    void set_settings(const QuantizationSettings& settings) { settings_ = settings; }

    /// Applies enters, then updates, then leaves. Never trusts the input: every
    /// inconsistency is returned (empty when none) and skipped; a malformed update
    /// column stops the updates there (later entries cannot be located); a snapshot of
    /// the acknowledged-delta wire (baseline_tick set) is refused whole.
    std::vector<SnapshotProblem> apply(const pb::Snapshot& snapshot);
    /// Compares the replica with the snapshot's audit poses (call after apply()):
    /// each must be within half a quantum/step (+1e-3). `max_error` receives the
    /// largest error seen, in quanta or steps (0 when the audit is empty).
    std::vector<SnapshotProblem> check_audit(const pb::Snapshot& snapshot, double& max_error) const;

    [[nodiscard]] bool knows(std::uint32_t id) const { return replica_.contains(id); }
    [[nodiscard]] std::size_t size() const { return replica_.size(); }
    /// Known entities on the heard tier (kept as snapshots apply: no scan).
    [[nodiscard]] std::size_t heard() const { return heard_; }
    /// The replica's pose of `id`, or nothing when the entity is not known.
    [[nodiscard]] std::optional<Pose> pose(std::uint32_t id) const;
    /// Every known entity (iterate with for_each(f(id, entity))).
    [[nodiscard]] const FlatIdMap<ReplicaEntity>& entities() const { return replica_; }

private:
    QuantizationSettings settings_;
    FlatIdMap<ReplicaEntity> replica_;
    std::size_t heard_ = 0; ///< entries of replica_ with tier == kHeardTier
};

} // namespace dsoc::protocol
