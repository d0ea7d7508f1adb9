#include "dsoc/protocol/compact_snapshot.hpp"

#include "dsoc/protocol/buffer_room.hpp"

#include "snapshot_rules.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>

namespace dsoc::protocol {

namespace {

/// How many update entries ahead the decoder asks the cache for the replica's slot.
constexpr int kPrefetchAhead = 8;

} // namespace

// --- encoder ---

void SnapshotEncoder::begin(std::uint64_t tick, pb::Snapshot& out, UpdateColumns* columns) {
    clear_to_need(out);
    out.set_server_tick(tick);
    columns_ = columns;
    if (columns_ != nullptr) {
        columns_->clear();
    }
    any_update_ = false;
    last_update_id_ = 0;
}

void SnapshotEncoder::enter(std::uint32_t id, const Pose& pose,
                            const std::array<float, 3>& half_extents, std::uint32_t kind,
                            std::uint8_t tier, pb::Snapshot& out) {
    const QuantizedPose q = quantize(pose, settings_, tier);
    (void)write_enter(id, q, tier, half_extents, kind, settings_, out);
    baseline_[id] = {q, tier};
}

std::uint32_t SnapshotEncoder::update(std::uint32_t id, const Pose& pose, std::uint8_t tier,
                                      pb::Snapshot& out) {
    return update_quantized(id, quantize(pose, settings_, tier), tier, out);
}

std::uint32_t SnapshotEncoder::update_quantized(std::uint32_t id, const QuantizedPose& q,
                                                std::uint8_t tier, pb::Snapshot& out) {
    Baseline& base = baseline_[id];
    std::array<std::int32_t, UpdateColumns::kMaxValuesPerEntry> values{};
    std::size_t count = 0;
    std::uint32_t fields = 0;
    if (tier != base.tier) {
        fields = kFieldRebase;
        values = {static_cast<std::int32_t>(tier), q.x, q.y, q.z, q.yaw, q.pitch};
        count = values.size();
    } else {
        // Each value is written and kept only when it changed: a select, not a branch
        // (which fields changed is a coin toss from entity to entity).
        const auto delta = [&](std::uint32_t bit, std::int32_t now, std::int32_t then,
                               std::int32_t value) {
            const bool changed = now != then;
            values[count] = value;
            count += changed ? 1 : 0;
            fields |= changed ? bit : 0;
        };
        const auto difference = [](std::int32_t now, std::int32_t then) {
            return static_cast<std::int32_t>(static_cast<std::int64_t>(now) - then);
        };
        delta(kFieldX, q.x, base.pose.x, difference(q.x, base.pose.x));
        delta(kFieldY, q.y, base.pose.y, difference(q.y, base.pose.y));
        delta(kFieldZ, q.z, base.pose.z, difference(q.z, base.pose.z));
        delta(kFieldYaw, q.yaw, base.pose.yaw,
              wrap_angle_delta(static_cast<std::int64_t>(q.yaw) - base.pose.yaw,
                               settings_.angle_steps));
        delta(kFieldPitch, q.pitch, base.pose.pitch, difference(q.pitch, base.pose.pitch));
    }
    if (fields == 0) {
        return 0;
    }
    const std::uint32_t id_delta = any_update_ ? id - last_update_id_ : id;
    if (columns_ != nullptr) {
        columns_->add(id_delta, fields, std::span<const std::int32_t>(values.data(), count));
    } else {
        auto* column = out.mutable_update_values();
        for (std::size_t k = 0; k < count; ++k) {
            column->Add(values[k]);
        }
        out.add_update_head(update_head(id_delta, fields));
        if (mask_apart(fields)) {
            out.add_update_fields(fields);
        }
    }
    any_update_ = true;
    last_update_id_ = id;
    // Field by field: a whole-struct temporary is built on the stack and copied back
    // with overlapping loads that wait for its stores to retire.
    base.pose = q;
    base.tier = tier;
    return fields;
}

void SnapshotEncoder::leave(std::uint32_t id, pb::Snapshot& out) {
    out.add_leave(id);
    baseline_.erase(id);
}

// --- decoder ---

std::vector<SnapshotProblem> SnapshotDecoder::apply(const pb::Snapshot& s) {
    std::vector<SnapshotProblem> problems;
    if (s.has_baseline_tick()) {
        problems.push_back({"malformed_update", "an acknowledged-delta snapshot (baseline_tick " +
                                                    std::to_string(s.baseline_tick()) +
                                                    ") on the reliable wire"});
        return problems;
    }
    const auto steps = static_cast<std::int64_t>(settings_.angle_steps);
    for (const pb::EntityState& e : s.enter()) {
        if (auto problem = enter_problem(e, settings_.angle_steps)) {
            problems.push_back(std::move(*problem));
            continue;
        }
        ReplicaEntity r;
        r.quantized = {e.x(), e.y(), e.z(), static_cast<std::int32_t>(e.yaw()), e.pitch()};
        r.tier = static_cast<std::uint8_t>(e.tier());
        r.enter_tier = r.tier;
        r.half_extents = {e.half_x(), e.half_y(), e.half_z()};
        r.kind = e.kind();
        if (!replica_.try_emplace(e.id(), r).second) {
            problems.push_back({"duplicate_enter", entity_name(e.id()) + " entered while known"});
        } else if (r.tier == kHeardTier) {
            ++heard_;
        }
    }

    UpdateEntryReader reader(s);
    const auto& values = s.update_values();
    // The ids a few entries ahead, only to prefetch their slots (500 clients' replicas
    // do not fit in cache): a hint from the heads alone, whatever they hold.
    int ahead = 0;
    std::uint64_t ahead_id = 0;
    const int heads = s.update_head_size();
    UpdateEntry e;
    for (int i = 0; reader.next(e); ++i) {
        for (; ahead < heads && ahead <= i + kPrefetchAhead; ++ahead) {
            const std::uint64_t step = s.update_head(ahead) >> kHeadFieldBitCount;
            ahead_id = ahead == 0 ? step : ahead_id + step;
            replica_.prefetch(static_cast<std::uint32_t>(ahead_id));
        }
        const std::uint32_t fields = e.fields;
        const int at = e.at;
        // Built only for a problem: this loop runs for every update a client receives.
        const auto where = [&] {
            return "update entry " + std::to_string(i) + " (" + entity_name(e.id) + ")";
        };
        ReplicaEntity* const known = replica_.find(e.id);
        if (known == nullptr) {
            problems.push_back({"update_for_unknown_entity", where() + " is not known"});
            continue;
        }
        ReplicaEntity& r = *known;
        if ((fields & kFieldRebase) != 0) {
            if (auto problem = rebase_problem(values.data() + at, settings_.angle_steps, where)) {
                problems.push_back(std::move(*problem));
                continue;
            }
            const std::int32_t tier = values[at];
            heard_ -= r.tier == kHeardTier ? 1 : 0;
            heard_ += tier == kHeardTier ? 1 : 0;
            r.tier = static_cast<std::uint8_t>(tier);
            r.quantized = {values[at + 1], values[at + 2], values[at + 3], values[at + 4],
                           values[at + 5]};
            continue;
        }
        if (r.tier == kHeardTier && (fields & (kFieldYaw | kFieldPitch)) != 0) {
            problems.push_back(
                {"angles_on_heard_tier", where() + ": view angles for a heard-only entity"});
            continue;
        }
        int k = at;
        bool in_range = true;
        auto add = [&](std::uint32_t bit, std::int32_t& field) {
            if ((fields & bit) == 0) {
                return;
            }
            const std::int64_t sum = static_cast<std::int64_t>(field) + values[k++];
            if (sum < -kMaxQuantizedCoordinate || sum > kMaxQuantizedCoordinate) {
                in_range = false;
                return;
            }
            field = static_cast<std::int32_t>(sum);
        };
        QuantizedPose q = r.quantized;
        add(kFieldX, q.x);
        add(kFieldY, q.y);
        add(kFieldZ, q.z);
        if ((fields & kFieldYaw) != 0) {
            q.yaw = add_angle_steps(q.yaw, values[k++], steps);
        }
        add(kFieldPitch, q.pitch);
        if (!in_range) {
            problems.push_back({"malformed_update", where() + ": a delta leaves the range"});
            continue;
        }
        // Only a pitch that arrives: the replica's own was checked when it came.
        if ((fields & kFieldPitch) != 0 && pitch_beyond(q.pitch, settings_.angle_steps)) {
            problems.push_back(
                {"malformed_update",
                 where() + ": " + pitch_beyond_detail(q.pitch, settings_.angle_steps)});
            continue;
        }
        r.quantized = q;
    }
    if (reader.problem()) {
        problems.push_back(*reader.problem());
    }

    for (const std::uint32_t id : s.leave()) {
        const ReplicaEntity* const known = replica_.find(id);
        if (known == nullptr) {
            problems.push_back(
                {"leave_for_unknown_entity", entity_name(id) + " left while unknown"});
            continue;
        }
        heard_ -= known->tier == kHeardTier ? 1 : 0;
        replica_.erase(id);
    }
    return problems;
}

std::vector<SnapshotProblem> SnapshotDecoder::check_audit(const pb::Snapshot& s,
                                                          double& max_error) const {
    std::vector<SnapshotProblem> problems;
    max_error = 0.0;
    for (const pb::AuditPose& a : s.audit()) {
        const ReplicaEntity* const known = replica_.find(a.id());
        check_audit_pose(a, known != nullptr ? &known->quantized : nullptr,
                         known != nullptr ? known->tier : 0, settings_, max_error, problems);
    }
    return problems;
}

std::optional<Pose> SnapshotDecoder::pose(std::uint32_t id) const {
    const ReplicaEntity* const known = replica_.find(id);
    if (known == nullptr) {
        return std::nullopt;
    }
    return dequantize(known->quantized, settings_.quantum(known->tier), settings_.angle_steps);
}

} // namespace dsoc::protocol
