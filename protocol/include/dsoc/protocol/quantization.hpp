#pragma once
// How entity poses travel in compact snapshots: positions as integer multiples of a
// quantum chosen per network level-of-detail tier, angles as integer steps of a full
// turn. A replica rebuilt from the integers is within half a quantum (and half an
// angle step) of the server's pose. Pure functions; safe from any thread.

#include "dsoc/protocol/messages.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::protocol {

/// Network level-of-detail tiers of entities the client sees: 0 near (every tick), 1
/// mid, 2 far.
inline constexpr std::size_t kLodTiers = 3;
/// The tier of an entity the client hears but does not see: positions in
/// QuantizationSettings::heard_quantum, angles never sent (always 0).
inline constexpr std::uint8_t kHeardTier = 3;
/// Every tier: the three of sight, then the heard tier.
inline constexpr std::size_t kTiers = 4;

/// log2 of update_interval(`tier`).
[[nodiscard]] constexpr unsigned update_interval_shift(std::uint8_t tier) {
    return tier < 2 ? tier : 2;
}
/// How often an entity on `tier` (< kTiers) is updated: every 1st, 2nd, 4th, 4th tick.
/// [Units: ticks]
[[nodiscard]] constexpr std::uint64_t update_interval(std::uint8_t tier) {
    return std::uint64_t{1} << update_interval_shift(tier);
}
/// Whether a known entity `id` on `tier` (< kTiers) is updated in the snapshot of `tick`:
/// on every tick on tier 0, else on one tick in update_interval(tier), staggered by id so
/// a tier's entities spread over its interval. The rule of a client sent every tick (the
/// server's plain replication and the evaluation's byte count); see due_since() for a
/// client sent more rarely.
[[nodiscard]] constexpr bool due_at(std::uint32_t id, std::uint8_t tier, std::uint64_t tick) {
    return ((tick + id) & (update_interval(tier) - 1)) == 0;
}
/// Largest |position / quantum| that travels; larger values are clamped (a world
/// that large is a server bug, the clamp only keeps the arithmetic defined).
inline constexpr std::int32_t kMaxQuantizedCoordinate = 1 << 30;

struct QuantizationSettings {
    /// Position quantum per tier, near to far. [Units: world units]
    /// [Limit: 1/1024..64 each, non-decreasing from near to far]
    std::array<float, kLodTiers> position_quantum{0.125f, 0.5f, 1.0f};
    /// Steps per full turn for yaw and pitch (4096: 0.088 degrees). [Limit: 256..65536]
    std::uint32_t angle_steps = 4096;
    /// Position quantum of the heard tier: where a sound comes from, no finer.
    /// [Units: world units] [Limit: position_quantum far..1024]
    float heard_quantum = 64.0f;

    /// The position quantum of `tier` (< kTiers).
    [[nodiscard]] float quantum(std::uint8_t tier) const {
        return tier == kHeardTier ? heard_quantum : position_quantum[tier];
    }
};

/// Every problem with the settings, each naming the field and why; empty when usable.
/// `prefix` is put before each field name (e.g. "quantization.").
[[nodiscard]] std::vector<std::string> validate(const QuantizationSettings& settings,
                                                const std::string& prefix = "");

void to_message(const QuantizationSettings& settings, pb::Quantization& out);
/// Reads a peer's settings; false with `why` set when they are unusable (wrong tier
/// count, a quantum or step count outside the limits).
[[nodiscard]] bool from_message(const pb::Quantization& message, QuantizationSettings& out,
                                std::string& why);

/// An entity's pose. [Units: world units, degrees; yaw in [-180, 180), pitch in [-90, 90]]
struct Pose {
    float x = 0.0f;
    float y = 0.0f;
    float z = 0.0f;
    float yaw_deg = 0.0f;
    float pitch_deg = 0.0f;
};

/// A pose as it travels. Positions in quanta; yaw in steps, [0, angle_steps); pitch in
/// steps, signed.
struct QuantizedPose {
    std::int32_t x = 0;
    std::int32_t y = 0;
    std::int32_t z = 0;
    std::int32_t yaw = 0;
    std::int32_t pitch = 0;
    friend bool operator==(const QuantizedPose&, const QuantizedPose&) = default;
};

/// Nearest quantized pose (round half away from zero). `quantum` > 0, `steps` >= 1;
/// non-finite inputs become 0.
[[nodiscard]] QuantizedPose quantize(const Pose& pose, float quantum, std::uint32_t steps);
/// The pose a quantized pose stands for; yaw in [-180, 180).
[[nodiscard]] Pose dequantize(const QuantizedPose& q, float quantum, std::uint32_t steps);
/// The largest |pitch| in steps of a quantized pose whose pitch is within [-90, 90]
/// degrees: a quarter of `steps`, rounded half up as quantize() rounds. A received pitch
/// beyond it is malformed (docs/protocol.md).
[[nodiscard]] constexpr std::int32_t max_pitch_steps(std::uint32_t steps) {
    return static_cast<std::int32_t>((steps + 2) / 4);
}
/// quantize() on `tier` (< kTiers) of `settings`: the heard tier drops the angles (0).
[[nodiscard]] QuantizedPose quantize(const Pose& pose, const QuantizationSettings& settings,
                                     std::uint8_t tier);
/// Quantized position of a box half extent, rounded up so the replica's box is
/// never smaller than the server's.
[[nodiscard]] std::uint32_t quantize_extent(float half_extent, float quantum);

/// Largest difference between `replica` and `exact`, in quanta for positions and in
/// angle steps for angles (yaw compared around the circle). A replica rebuilt from
/// quantize(exact) gives at most 0.5 (plus float rounding, under 1e-3 for worlds
/// within +-2^20 quanta).
[[nodiscard]] double quantization_error(const Pose& replica, const Pose& exact, float quantum,
                                        std::uint32_t steps);

} // namespace dsoc::protocol
