#pragma once
// Acknowledged-delta snapshots (docs/protocol.md, "Acknowledged deltas"): the sender's and
// the receiver's halves of one connection's entity replica over a transport that may
// lose, duplicate or reorder snapshots (UDP). Each snapshot is coded against the newest
// frame (delta_frame.hpp) the client has acknowledged, or against nothing, and says the
// whole set the client knows at its tick: entities not in the baseline enter with full
// state, the baseline's entities not wanted any more leave, and every other one is carried
// at its predicted position plus the residual its update entry holds (none: the
// prediction was exact), or, on a coarse tier between the ticks it is due, held as it was. So a
// lost snapshot needs no repair, never leaves a stale entity and never loses a leave: the next one
// is coded against a frame the client has.
//
// Threading: neither class is thread-safe; one per connection. Distinct instances may be
// used concurrently.

#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/delta_frame.hpp"
#include "dsoc/protocol/messages.hpp"
#include "dsoc/protocol/quantization.hpp"
#include "dsoc/protocol/update_columns.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace dsoc::protocol {

/// The most entities one acknowledged-delta snapshot enters (the sender's rule; a
/// receiver takes any number). An enter carries an entity's whole state, several times
/// the bytes of a carried one, so a client that comes into view of a crowd (its first
/// snapshot, a teleport) gets the crowd over a few round trips instead of a snapshot too
/// large to send (datagram.hpp's kMaxSnapshotBytes) that would be dropped again every
/// tick. [Units: entities]
inline constexpr std::size_t kMaxEntersPerSnapshot = 1024;

/// What one acknowledged-delta snapshot holds.
struct AckedSnapshotCounts {
    std::uint32_t enters = 0;
    std::uint32_t leaves = 0;
    std::uint32_t entries = 0; ///< update entries written
    /// Entities carried from the baseline whose position is not the baseline's, with an
    /// entry or predicted exactly (the updates a sender without prediction would write).
    std::uint32_t moved = 0;
    bool coded_against_baseline = false;
    /// Ticks from the baseline to the snapshot (how late the acknowledgement was); 0
    /// when coded against nothing.
    std::uint64_t baseline_age = 0;
};

class AckedSnapshotEncoder {
public:
    /// `settings` must have passed validate().
    explicit AckedSnapshotEncoder(const QuantizationSettings& settings) : settings_(settings) {}

    /// Clears `out` and starts the snapshot of `tick` (greater than every earlier one's),
    /// coded against the frame of `acked` (the newest tick the client acknowledged) when
    /// this encoder still holds it and it is less than kAckedHistory ticks older; against
    /// nothing otherwise (every entity enters). `acked` never goes back from one call to
    /// the next (an older acknowledgement arriving late is not newest): the frames older
    /// than it are forgotten, and so a snapshot's baseline is never older than an earlier
    /// one's, as docs/protocol.md promises the client.
    /// `columns` (optional; cleared here) takes the update entries in wire form instead of
    /// `out`'s repeated fields (append_snapshot_envelope() writes the two together).
    void begin(std::uint64_t tick, std::optional<std::uint64_t> acked, pb::Snapshot& out,
               UpdateColumns* columns = nullptr);
    /// One entity the client is to know, in increasing id order: `pose` quantized on
    /// `tier` (< kTiers; quantize(pose, settings(), tier)), `half_extents` in world units.
    /// On a tier t > 0 an entity is updated only when due (due_since(): a multiple of
    /// update_interval(t), less its id, passed since its pose was last set); on the other
    /// ticks the frame holds it as it was (FrameEntity::held_ticks).
    void add(std::uint32_t id, const QuantizedPose& pose, std::uint8_t tier, std::uint32_t kind,
             const std::array<float, 3>& half_extents, pb::Snapshot& out);
    /// add() in two steps, for a caller whose kind and size of an entity cost a lookup
    /// that only an enter needs: carry() adds the entity when the baseline holds it and
    /// returns true; otherwise it writes nothing for it and returns false, and either
    /// enter() (same id, pose and tier) follows before the next entity, or the entity is
    /// left out of this snapshot (not in its frame: the client does not know it).
    [[nodiscard]] bool carry(std::uint32_t id, const QuantizedPose& pose, std::uint8_t tier,
                             pb::Snapshot& out);
    void enter(std::uint32_t id, const QuantizedPose& pose, std::uint8_t tier, std::uint32_t kind,
               const std::array<float, 3>& half_extents, pb::Snapshot& out);
    /// carry() without an update entry, for a sender out of room: when the baseline holds
    /// the entity, adds it as the client takes it from a snapshot with no entry for it
    /// (held when not due, at its prediction when due; on its baseline tier, so a rebase is
    /// not written either) and returns true; otherwise writes nothing and returns false. The
    /// frame then holds what the client will hold, and the next snapshot's entry is coded
    /// against it (or against an older frame, as any entry).
    [[nodiscard]] bool carry_unwritten(std::uint32_t id, pb::Snapshot& out);
    /// Writes the leaves of the baseline's entities not added yet: after it, no entity is
    /// added to this snapshot (finish() or restart() follows). Then `out` (and the columns)
    /// hold the whole snapshot, to be sized.
    void leave_the_rest(pb::Snapshot& out);
    /// Starts the snapshot begun last again, empty (same tick, same columns), coded against
    /// the same frame, or against nothing when `against_nothing`: for a sender that found
    /// the first try too large and writes it again with less.
    void restart(pb::Snapshot& out, bool against_nothing);
    /// Ends the snapshot (the baseline's entities not added leave) and keeps its frame.
    AckedSnapshotCounts finish(pb::Snapshot& out);

    /// What the snapshot holds so far.
    [[nodiscard]] const AckedSnapshotCounts& counts() const { return counts_; }
    /// The entity the last carry(), carry_unwritten() or enter() added, as this snapshot's
    /// frame holds it (held_ticks > 0: carried without being due).
    [[nodiscard]] const FrameEntity& last_added() const { return next_->entities.back(); }

    /// The frame of `tick` as the client holds it once it applies that snapshot, while
    /// this encoder keeps it (not once a newer tick is acknowledged).
    [[nodiscard]] const DeltaFrame* frame(std::uint64_t tick) const { return frames_.find(tick); }
    [[nodiscard]] const QuantizationSettings& settings() const { return settings_; }
    /// Between begin() and finish(): the frame this snapshot is coded against (its
    /// entities in increasing id order), or nullptr when coded against nothing.
    [[nodiscard]] const DeltaFrame* baseline() const { return base_; }

private:
    void leave_baseline_below(std::uint32_t id, pb::Snapshot& out);
    /// leave_baseline_below(id), then whether the baseline's next entity is `id`.
    bool meets_baseline(std::uint32_t id, pb::Snapshot& out);
    void write_entry(std::uint32_t id, std::uint32_t fields, const std::int32_t* values,
                     std::size_t count, pb::Snapshot& out);

    QuantizationSettings settings_;
    FrameRing frames_;
    DeltaFrame* next_ = nullptr; ///< in frames_, between begin() and finish()
    const DeltaFrame* base_ = nullptr;
    UpdateColumns* columns_ = nullptr; ///< this snapshot's, or null: into its repeated fields
    std::size_t base_at_ = 0;          ///< the next baseline entity not yet met
    std::uint64_t ticks_since_base_ = 0;
    std::uint32_t last_entry_id_ = 0;
    AckedSnapshotCounts counts_;
};

class AckedSnapshotDecoder {
public:
    /// `settings`: the server's, from its ServerHello.
    explicit AckedSnapshotDecoder(const QuantizationSettings& settings = {})
        : settings_(settings) {}

    /// Decodes `snapshot` against the frame it names and, when nothing is wrong, makes
    /// its frame the newest. Never trusts the input: a snapshot not newer than the
    /// newest (stale_snapshot: a duplicate or a late one), coded against a frame this
    /// decoder does not hold (baseline_missing) or inconsistent in any way (the kinds of
    /// SnapshotDecoder::apply) is rejected whole and changes nothing; the problems say why.
    /// An applied snapshot's baseline is the oldest frame kept: a server never codes
    /// against an older one after it (docs/protocol.md).
    std::vector<SnapshotProblem> apply(const pb::Snapshot& snapshot);

    /// The newest frame applied (what the client acknowledges), or nullptr before any.
    [[nodiscard]] const DeltaFrame* newest() const {
        return newest_tick_ ? frames_.find(*newest_tick_) : nullptr;
    }
    [[nodiscard]] std::optional<std::uint64_t> newest_tick() const { return newest_tick_; }
    /// Where the newest frame expects `id` at its tick (a held entity's pose moved on by
    /// its prediction), or nothing when the entity is not known.
    [[nodiscard]] std::optional<Pose> pose(std::uint32_t id) const;
    /// The newest frame's entity `id`, or nullptr.
    [[nodiscard]] const FrameEntity* find(std::uint32_t id) const;
    /// Compares the newest frame against `snapshot`'s audit poses (the snapshot just
    /// applied), as SnapshotDecoder::check_audit does: every audited entity known, not
    /// heard-only, within half a quantum. `max_error`: the largest error, in quanta.
    [[nodiscard]] std::vector<SnapshotProblem> check_audit(const pb::Snapshot& snapshot,
                                                           double& max_error) const;
    [[nodiscard]] const QuantizationSettings& settings() const { return settings_; }

private:
    QuantizationSettings settings_;
    FrameRing frames_;
    std::optional<std::uint64_t> newest_tick_;
    std::vector<UpdateEntry> entries_; ///< scratch of apply()
};

} // namespace dsoc::protocol
