#pragma once
// Acknowledged-delta frames (docs/protocol.md, "Acknowledged deltas"): what both ends of
// a connection hold for one snapshot tick. A frame lists every entity the client knew
// after that snapshot, with the pose it was last given (a coarse-tier entity is held
// between the ticks it is due) and a velocity both ends derive from it, so that a later snapshot
// can be coded against any frame the client has acknowledged (a lost snapshot is never needed
// again), its positions as residuals against one prediction rule: an entity moving steadily costs
// no bytes.
//
// Pure data and integer arithmetic: both ends compute bit-identical frames.
//
// Threading: none; one ring per connection end.

#include "dsoc/protocol/buffer_room.hpp"
#include "dsoc/protocol/quantization.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace dsoc::protocol {

/// Frames each end keeps (as Quake 3's PACKET_BACKUP): a snapshot is coded against a
/// frame at most kAckedHistory - 1 ticks older, or against nothing. [Units: ticks]
inline constexpr std::size_t kAckedHistory = 32;

/// Fixed-point scale of FrameEntity::velocity: 1/256 of a quantum per tick.
inline constexpr std::int64_t kVelocityScale = 256;

/// One entity of a frame.
struct FrameEntity {
    QuantizedPose pose; ///< on `tier`
    /// The position's change per tick, measured over the `motion_ticks` ticks up to when
    /// `pose` was set (this frame's tick - held_ticks), in quanta of `tier` / kVelocityScale: zero
    /// when the entity entered or changed tier.
    std::array<std::int32_t, 3> velocity{};
    /// How the z velocity changed per tick since the one before (a fall, a jump's arc),
    /// in quanta of `tier` / kVelocityScale per tick. Vertical only: gravity is the steady
    /// acceleration of walking entities, and horizontally the same estimate mostly
    /// amplifies the quantization's jitter (it cost bytes on arena-64).
    std::int32_t fall_rate = 0;
    /// How far the yaw turned per tick over the same ticks (the shorter way round), in
    /// angle steps / kVelocityScale.
    std::int32_t turn_rate = 0;
    std::uint32_t id = 0;
    std::uint32_t kind = 0;
    std::array<std::uint32_t, 3> half_extents{}; ///< in quanta of `enter_tier`
    std::uint8_t tier = 0;                       ///< < kTiers
    std::uint8_t enter_tier = 0;
    std::uint8_t motion_ticks = 0; ///< over how many ticks `velocity` was measured; 0: none
    /// Ticks from when `pose` and the motion were set (an enter, a rebase, a tick the
    /// entity was due) to this frame's tick: a coarse-tier entity is held, not moved on,
    /// between the ticks it is due. < update_interval(tier), so at most kMaxHeldTicks.
    std::uint8_t held_ticks = 0;
    friend bool operator==(const FrameEntity&, const FrameEntity&) = default;
};

/// The most ticks a frame entity is held: update_interval() of the coarsest tier, less 1.
inline constexpr std::uint64_t kMaxHeldTicks = update_interval(kHeardTier) - 1;
/// The most ticks a prediction spans: a baseline kAckedHistory - 1 ticks old whose entity
/// was held kMaxHeldTicks. [Units: ticks]
inline constexpr std::uint64_t kMaxPredictedTicks = kAckedHistory - 1 + kMaxHeldTicks;
static_assert(kMaxPredictedTicks <= 255, "motion_ticks holds a prediction's span");

/// Whether entity `id` on `tier` (< kTiers) is due at `tick`, its pose last set at
/// `set_tick` (< tick): whether a tick in (set_tick, tick] is a multiple of
/// update_interval(tier) after adding `id`. An entity sent every tick is due on every
/// update_interval()-th tick, staggered by its id; one sent more rarely (a client the
/// server paces) on the first snapshot after such a tick, so no entity waits longer than
/// its interval whatever ticks a client is sent.
[[nodiscard]] constexpr bool due_since(std::uint32_t id, std::uint8_t tier, std::uint64_t set_tick,
                                       std::uint64_t tick) {
    const unsigned shift = update_interval_shift(tier);
    return ((tick + id) >> shift) != ((set_tick + id) >> shift);
}

/// Every entity the client knew after the snapshot of `tick`, in increasing id order.
struct DeltaFrame {
    std::uint64_t tick = 0;
    std::vector<FrameEntity> entities;
};

/// `a` / `b` (b > 0) rounded to the nearest integer, halves away from zero.
[[nodiscard]] constexpr std::int64_t divide_rounded(std::int64_t a, std::int64_t b) {
    return a >= 0 ? (a + b / 2) / b : -((-a + b / 2) / b);
}

/// Where `base` is expected `ticks` (1..kMaxPredictedTicks) after its pose was set (its
/// frame's tick - base.held_ticks): its position
/// moved on by its velocity, z also by its fall rate (each coordinate within
/// +-kMaxQuantizedCoordinate), its yaw turned on by its turn rate (wrapped into
/// [0, angle_steps)), its pitch as it was.
[[nodiscard]] QuantizedPose predict(const FrameEntity& base, std::uint64_t ticks,
                                    std::uint32_t angle_steps);

/// Forgets how `e` moved (it entered, or changed tier and so quanta): it is predicted
/// where it is until set_motion() measures it again.
inline void clear_motion(FrameEntity& e) {
    e.velocity = {};
    e.fall_rate = 0;
    e.turn_rate = 0;
    e.motion_ticks = 0;
}

/// Sets `e`'s velocity, fall rate (against its velocity before), turn rate and
/// motion_ticks to how its pose went from `from` to e.pose in `ticks`
/// (1..kMaxPredictedTicks) ticks.
void set_motion(FrameEntity& e, const QuantizedPose& from, std::uint64_t ticks,
                std::uint32_t angle_steps);

/// The frames one connection end holds, at most kAckedHistory, each in the slot of its
/// tick modulo the capacity, and the memory of the frames it no longer needs.
///
/// A frame is built in the memory forgotten most recently: with acknowledgements
/// arriving, that is the frame just older than the baseline, read a tick or two ago and
/// still in cache, where a slot's own old memory was last used kAckedHistory ticks ago
/// (500 clients' frames do not fit in cache, and writing a frame into cold memory was most
/// of the codec's cost).
///
/// Memory follows the frames' sizes (buffer_room.hpp): a buffer with room for more than
/// twice the newest frame's entities (and kSlackEntities) is given back, not kept, so a connection
/// whose set once peaked does not hold that peak's memory for the rest of its life (a ten-minute
/// soak's RSS rose with every client's largest set so far).
class FrameRing {
public:
    /// The frame of `tick`, or nullptr when it was never stored, has been replaced or
    /// forgotten.
    [[nodiscard]] const DeltaFrame* find(std::uint64_t tick) const {
        const Slot& s = slots_[tick % kAckedHistory];
        return s.used && s.frame.tick == tick ? &s.frame : nullptr;
    }
    /// The frame of `tick` (newer than every stored one) to fill: empty, in the memory
    /// forgotten most recently, or, with none to reuse, in new memory with room for the
    /// newest frame's entities and kSlackEntities. Valid until the next start(); commit()
    /// stores it.
    DeltaFrame& start(std::uint64_t tick);
    /// Stores the frame start() gave, in its slot, replacing the frame kAckedHistory or
    /// more ticks older.
    void commit();
    /// Forgets every frame older than `tick`: an end that knows no snapshot will be coded
    /// against them any more hands their memory to the next frames.
    void forget_older_than(std::uint64_t tick);
    /// Entities the ring's buffers have room for, held frames' and spare: its memory is
    /// this times sizeof(FrameEntity).
    [[nodiscard]] std::size_t capacity() const;

    /// Room kept beyond twice the newest frame's entities. [Units: entities]
    static constexpr std::size_t kSlackEntities = 64;

private:
    /// Forgotten buffers kept for reuse beyond those in the slots (more are freed, the
    /// coldest first). With acknowledgements arriving every tick one frame is forgotten
    /// and one started per tick, so two suffice; the burst of frames a late client's
    /// catch-up forgets at once goes back to the allocator, where every connection can
    /// reuse it (kept per connection, each one's worst moment stayed allocated: a soak's
    /// RSS crept up with every client that once fell behind).
    static constexpr std::size_t kMaxSpare = 2;

    struct Slot {
        DeltaFrame frame;
        bool used = false;
    };
    void keep_spare(std::vector<FrameEntity>&& memory, bool warm);
    /// Whether a buffer of `capacity` entities is more than the newest frame needs.
    [[nodiscard]] bool oversized(std::size_t capacity) const {
        return room_oversized(capacity, newest_size_, kSlackEntities);
    }

    std::array<Slot, kAckedHistory> slots_{};
    DeltaFrame next_;
    std::vector<std::vector<FrameEntity>> spare_; ///< coldest first
    std::size_t newest_size_ = 0;                 ///< entities of the frame committed last
};

} // namespace dsoc::protocol
