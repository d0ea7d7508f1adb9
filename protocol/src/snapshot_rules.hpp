#pragma once
// Rules both snapshot codecs (compact_snapshot.hpp, acked_snapshot.hpp) share: angle
// steps as they travel (a yaw is a step in [0, steps) and wraps; its deltas go the
// shorter way round) and which update entries are well formed. Pure functions.

#include "dsoc/protocol/compact_snapshot.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::protocol {

/// `delta` wrapped into [steps/2 - steps, steps/2) (integer halves).
inline std::int32_t wrap_angle_delta(std::int64_t delta, std::uint32_t steps) {
    const auto n = static_cast<std::int64_t>(steps);
    const std::int64_t half = n / 2;
    std::int64_t d = delta;
    if (d <= -n || d >= n) {
        d = ((d % n) + n) % n; // not between two quantized yaws: the general rule
    }
    if (d >= half) {
        d -= n;
    } else if (d < half - n) {
        d += n;
    }
    return static_cast<std::int32_t>(d);
}

/// `yaw` + `delta` wrapped into [0, steps). An encoder's deltas keep the sum within
/// one turn of the range (wrap_angle_delta), so that case costs no division; any other
/// delta (a hostile sender's) takes the general rule.
inline std::int32_t add_angle_steps(std::int32_t yaw, std::int32_t delta, std::int64_t steps) {
    std::int64_t sum = static_cast<std::int64_t>(yaw) + delta;
    sum += sum < 0 ? steps : 0;
    sum -= sum >= steps ? steps : 0;
    if (sum < 0 || sum >= steps) {
        sum = ((sum % steps) + steps) % steps;
    }
    return static_cast<std::int32_t>(sum);
}

/// Whether `fields` is a well-formed Snapshot.update_fields entry: not empty, only known
/// bits, and a rebase alone.
[[nodiscard]] inline bool valid_update_fields(std::uint32_t fields) {
    constexpr std::uint32_t kKnownFields =
        kFieldX | kFieldY | kFieldZ | kFieldYaw | kFieldPitch | kFieldRebase;
    return fields != 0 && (fields & ~kKnownFields) == 0 &&
           ((fields & kFieldRebase) == 0 || fields == kFieldRebase);
}

/// How many update_values an entry with valid_update_fields() `fields` carries: a rebase
/// the tier and five absolute values, otherwise one value per field.
[[nodiscard]] inline int update_value_count(std::uint32_t fields) {
    // A table, not std::popcount: built without -mpopcnt that is a call into libgcc, for
    // every entry a client reads.
    static constexpr auto kBitsSet = [] {
        std::array<std::uint8_t, 32> bits{};
        for (std::uint32_t f = 0; f < bits.size(); ++f) {
            bits[f] = static_cast<std::uint8_t>(std::popcount(f));
        }
        return bits;
    }();
    static_assert(((kFieldX | kFieldY | kFieldZ | kFieldYaw | kFieldPitch) >> 5) == 0);
    return (fields & kFieldRebase) != 0 ? 6 : kBitsSet[fields & 31u];
}

/// "entity <id>", as problems name an entity.
[[nodiscard]] inline std::string entity_name(std::uint32_t id) {
    return "entity " + std::to_string(id);
}

/// Appends to `out` the enter of `id` with quantized pose `q` on `tier`, its half extents
/// (world units) quantized on the same tier: what either encoder sends for an entity
/// new to the client. Returns the quantized half extents.
inline std::array<std::uint32_t, 3>
write_enter(std::uint32_t id, const QuantizedPose& q, std::uint8_t tier,
            const std::array<float, 3>& half_extents, std::uint32_t kind,
            const QuantizationSettings& settings, pb::Snapshot& out) {
    const float quantum = settings.quantum(tier);
    const std::array<std::uint32_t, 3> half{quantize_extent(half_extents[0], quantum),
                                            quantize_extent(half_extents[1], quantum),
                                            quantize_extent(half_extents[2], quantum)};
    pb::EntityState& s = *out.add_enter();
    s.set_id(id);
    s.set_tier(tier);
    s.set_x(q.x);
    s.set_y(q.y);
    s.set_z(q.z);
    s.set_yaw(static_cast<std::uint32_t>(q.yaw));
    s.set_pitch(q.pitch);
    s.set_half_x(half[0]);
    s.set_half_y(half[1]);
    s.set_half_z(half[2]);
    s.set_kind(kind);
    return half;
}

/// Walks a snapshot's update entries in order, checking their form as it goes: ids
/// increasing, masks well formed and each written the one way, values and masks apart
/// neither running out nor left over. One pass, nothing stored: the client's decoder
/// runs it over every update it receives.
class UpdateEntryReader {
public:
    explicit UpdateEntryReader(const pb::Snapshot& s)
        : heads_(s.update_head().data()), masks_(s.update_fields().data()),
          head_count_(s.update_head_size()), mask_count_(s.update_fields_size()),
          value_count_(s.update_values_size()) {}

    /// The next entry into `e`; false at the end, or at a malformed entry (the later
    /// ones cannot be located): then problem() says why.
    bool next(UpdateEntry& e) {
        if (index_ >= head_count_) {
            if (index_ == head_count_) {
                index_ = head_count_ + 1; // checked once
                check_nothing_left();
            }
            return false;
        }
        const std::uint64_t head = heads_[index_];
        const std::uint64_t step = head >> kHeadFieldBitCount;
        id_ = index_ == 0 ? step : id_ + step;
        if ((index_ > 0 && step == 0) || id_ > 0xffffffffu) {
            return stop("ids must increase");
        }
        auto fields = static_cast<std::uint32_t>(head & kHeadFields);
        if (fields == 0) {
            if (masks_apart_ == mask_count_) {
                return stop("update_fields ends early");
            }
            fields = masks_[masks_apart_++];
            if (!mask_apart(fields)) {
                return stop("mask " + std::to_string(fields) + " belongs in update_head");
            }
        }
        if (!valid_update_fields(fields)) {
            return stop("bad field mask " + std::to_string(fields));
        }
        const int count = update_value_count(fields);
        if (value_count_ - values_ < count) {
            return stop("update_values ends early");
        }
        e = {static_cast<std::uint32_t>(id_), fields, values_};
        values_ += count;
        ++index_;
        return true;
    }

    /// Why next() stopped early, if it did.
    [[nodiscard]] const std::optional<SnapshotProblem>& problem() const { return problem_; }

private:
    bool stop(const std::string& why) {
        problem_ = SnapshotProblem{"malformed_update",
                                   "update entry " + std::to_string(index_) + " (" +
                                       entity_name(static_cast<std::uint32_t>(id_)) + "): " + why};
        index_ = head_count_ + 1;
        return false;
    }
    void check_nothing_left() {
        if (masks_apart_ != mask_count_) {
            problem_ =
                SnapshotProblem{"malformed_update", std::to_string(mask_count_ - masks_apart_) +
                                                        " update_fields left over"};
        } else if (values_ != value_count_) {
            problem_ = SnapshotProblem{"malformed_update", std::to_string(value_count_ - values_) +
                                                               " update_values left over"};
        }
    }

    const std::uint64_t* heads_;
    const std::uint32_t* masks_;
    int head_count_;
    int mask_count_;
    int value_count_;
    int index_ = 0;
    int masks_apart_ = 0;
    int values_ = 0;
    std::uint64_t id_ = 0;
    std::optional<SnapshotProblem> problem_;
};

/// Every update entry of `s` into `entries` (cleared first) with UpdateEntryReader;
/// returns its problem, the entries before it in `entries`.
inline std::optional<SnapshotProblem> read_update_entries(const pb::Snapshot& s,
                                                          std::vector<UpdateEntry>& entries) {
    entries.clear();
    UpdateEntryReader reader(s);
    for (UpdateEntry e; reader.next(e);) {
        entries.push_back(e);
    }
    return reader.problem();
}

/// Whether a received pitch (steps) is beyond a quarter turn either way: what no pose
/// with a pitch within [-90, 90] degrees quantizes to (max_pitch_steps).
[[nodiscard]] inline bool pitch_beyond(std::int64_t pitch, std::uint32_t steps) {
    return pitch < -max_pitch_steps(steps) || pitch > max_pitch_steps(steps);
}

/// "pitch step P beyond +-M (a quarter turn)", for a problem's detail.
[[nodiscard]] inline std::string pitch_beyond_detail(std::int64_t pitch, std::uint32_t steps) {
    return "pitch step " + std::to_string(pitch) + " beyond +-" +
           std::to_string(max_pitch_steps(steps)) + " (a quarter turn)";
}

/// What is wrong with an entering entity's state, if anything: its tier, angles on the
/// heard tier, a position beyond +-kMaxQuantizedCoordinate, a half extent beyond
/// kMaxQuantizedCoordinate (quantize_extent() sends no larger), a yaw step outside
/// [0, steps), or a pitch beyond a quarter turn. The kind is the game's own value and
/// passes as it is.
[[nodiscard]] inline std::optional<SnapshotProblem> enter_problem(const pb::EntityState& e,
                                                                  std::uint32_t steps) {
    if (e.tier() >= kTiers) {
        return SnapshotProblem{"bad_tier", entity_name(e.id()) + " enters on tier " +
                                               std::to_string(e.tier()) + "; tiers are 0..3"};
    }
    if (e.tier() == kHeardTier && (e.yaw() != 0 || e.pitch() != 0)) {
        return SnapshotProblem{"angles_on_heard_tier",
                               entity_name(e.id()) + " enters heard-only with view angles"};
    }
    const auto outside = [](std::int32_t v) {
        return v < -kMaxQuantizedCoordinate || v > kMaxQuantizedCoordinate;
    };
    if (outside(e.x()) || outside(e.y()) || outside(e.z())) {
        return SnapshotProblem{"malformed_update",
                               entity_name(e.id()) + " enters beyond +-2^30 quanta"};
    }
    for (const std::uint32_t half : {e.half_x(), e.half_y(), e.half_z()}) {
        if (half > static_cast<std::uint32_t>(kMaxQuantizedCoordinate)) {
            return SnapshotProblem{"malformed_update",
                                   entity_name(e.id()) + " enters with half extent " +
                                       std::to_string(half) + " quanta, beyond 2^30"};
        }
    }
    if (e.yaw() >= steps) {
        return SnapshotProblem{"malformed_update", entity_name(e.id()) + " enters with yaw step " +
                                                       std::to_string(e.yaw()) +
                                                       " >= " + std::to_string(steps)};
    }
    if (pitch_beyond(e.pitch(), steps)) {
        return SnapshotProblem{"malformed_update", entity_name(e.id()) + " enters with " +
                                                       pitch_beyond_detail(e.pitch(), steps)};
    }
    return std::nullopt;
}

/// What is wrong with a rebase entry's values (the new tier, x, y, z, yaw, pitch), if
/// anything (the tier, angles on the heard tier, the yaw step, a position beyond
/// +-kMaxQuantizedCoordinate, a pitch beyond a quarter turn); `where()` names the entry
/// (called only for a problem).
template <class Where>
[[nodiscard]] std::optional<SnapshotProblem> rebase_problem(const std::int32_t* values,
                                                            std::uint32_t steps, Where&& where) {
    const std::int32_t tier = values[0];
    const std::int32_t yaw = values[4];
    if (tier < 0 || static_cast<std::size_t>(tier) >= kTiers) {
        return SnapshotProblem{"bad_tier", where() + ": rebase to tier " + std::to_string(tier)};
    }
    if (tier == kHeardTier && (yaw != 0 || values[5] != 0)) {
        return SnapshotProblem{"angles_on_heard_tier",
                               where() + ": rebase to heard with view angles"};
    }
    if (yaw < 0 || static_cast<std::uint32_t>(yaw) >= steps) {
        return SnapshotProblem{"malformed_update",
                               where() + ": rebase yaw step " + std::to_string(yaw)};
    }
    for (int k = 1; k <= 3; ++k) {
        if (values[k] < -kMaxQuantizedCoordinate || values[k] > kMaxQuantizedCoordinate) {
            return SnapshotProblem{"malformed_update", where() + ": rebase beyond +-2^30 quanta"};
        }
    }
    if (pitch_beyond(values[5], steps)) {
        return SnapshotProblem{"malformed_update",
                               where() + ": rebase " + pitch_beyond_detail(values[5], steps)};
    }
    return std::nullopt;
}

/// Checks one audit pose against what the replica holds of its entity (`quantized` on
/// `tier`, or nullptr when the entity is not known): known, not heard-only (its exact
/// pose must never be sent), within half a quantum. Raises `max_error` (quanta).
inline void check_audit_pose(const pb::AuditPose& a, const QuantizedPose* quantized,
                             std::uint8_t tier, const QuantizationSettings& settings,
                             double& max_error, std::vector<SnapshotProblem>& problems) {
    constexpr double kAllowed = 0.5 + 1e-3;
    if (quantized == nullptr) {
        problems.push_back({"audit_for_unknown_entity", entity_name(a.id()) + " is not known"});
        return;
    }
    if (tier == kHeardTier) {
        problems.push_back({"audit_of_heard_entity",
                            entity_name(a.id()) + " is heard-only; its exact pose was sent"});
        return;
    }
    const float quantum = settings.position_quantum[tier];
    const Pose replica = dequantize(*quantized, quantum, settings.angle_steps);
    const Pose exact{a.x(), a.y(), a.z(), a.yaw(), a.pitch()};
    const double error = quantization_error(replica, exact, quantum, settings.angle_steps);
    max_error = std::max(max_error, error);
    if (error > kAllowed) {
        problems.push_back({"pose_beyond_quantization",
                            entity_name(a.id()) + " replica is " + std::to_string(error) +
                                " quanta from the server's pose (allowed 0.5)"});
    }
}

} // namespace dsoc::protocol
