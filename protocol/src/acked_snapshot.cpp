#include "dsoc/protocol/acked_snapshot.hpp"

#include "dsoc/protocol/buffer_room.hpp"

#include "snapshot_rules.hpp"

#include <algorithm>
#include <cassert>
#include <limits>

namespace dsoc::protocol {

// --- frames ---

namespace {

std::int32_t clamp_coordinate(std::int64_t v) {
    return static_cast<std::int32_t>(
        std::clamp<std::int64_t>(v, -kMaxQuantizedCoordinate, kMaxQuantizedCoordinate));
}

bool fits_int32(std::int64_t v) {
    return v >= std::numeric_limits<std::int32_t>::min() &&
           v <= std::numeric_limits<std::int32_t>::max();
}

bool same_position(const QuantizedPose& a, const QuantizedPose& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

} // namespace

namespace {

// Inlined into the encoder's and the decoder's loops, which run them for every entity of
// every snapshot; the public predict() and set_motion() are the same code.
[[gnu::always_inline]] inline QuantizedPose predicted(const FrameEntity& base, std::uint64_t ticks,
                                                      std::uint32_t angle_steps) {
    const auto t = static_cast<std::int64_t>(ticks);
    // In halves, so that the fall's t (t + motion_ticks) / 2 is exact before the one
    // rounding: with the velocity the mean over the motion_ticks before the frame, a
    // constant acceleration a adds a t (t + motion_ticks) / 2 in t ticks.
    const auto moved = [t](std::int32_t at, std::int32_t rate, std::int64_t twice_more) {
        return clamp_coordinate(at +
                                divide_rounded(2 * static_cast<std::int64_t>(rate) * t + twice_more,
                                               2 * kVelocityScale));
    };
    const std::int64_t twice_fall =
        static_cast<std::int64_t>(base.fall_rate) * t * (t + base.motion_ticks);
    QuantizedPose p = base.pose;
    p.x = moved(p.x, base.velocity[0], 0);
    p.y = moved(p.y, base.velocity[1], 0);
    p.z = moved(p.z, base.velocity[2], twice_fall);
    p.yaw = add_angle_steps(p.yaw, moved(0, base.turn_rate, 0), angle_steps);
    return p;
}

[[gnu::always_inline]] inline void measure_motion(FrameEntity& e, const QuantizedPose& from,
                                                  std::uint64_t ticks, std::uint32_t angle_steps) {
    const auto t = static_cast<std::int64_t>(ticks);
    // Acknowledged every tick (t = 1, motion_ticks = 1) is the common case: its divisions
    // by 1 and 2 are exact, so it skips them (the same results, without a division by a
    // number only known at run time, for every entity of every snapshot at both ends).
    const auto per_tick = [t](std::int64_t change) __attribute__((always_inline)) {
        return clamp_coordinate(t == 1 ? change * kVelocityScale
                                       : divide_rounded(change * kVelocityScale, t));
    };
    const std::int32_t vz = per_tick(static_cast<std::int64_t>(e.pose.z) - from.z);
    // The old and the new mean z velocity stand (t + motion_ticks) / 2 ticks apart.
    const std::int64_t twice_change = (static_cast<std::int64_t>(vz) - e.velocity[2]) * 2;
    const std::int64_t apart = t + e.motion_ticks;
    e.fall_rate =
        e.motion_ticks == 0
            ? 0
            : clamp_coordinate(apart == 2 ? twice_change / 2 : divide_rounded(twice_change, apart));
    e.velocity = {per_tick(static_cast<std::int64_t>(e.pose.x) - from.x),
                  per_tick(static_cast<std::int64_t>(e.pose.y) - from.y), vz};
    e.turn_rate =
        per_tick(wrap_angle_delta(static_cast<std::int64_t>(e.pose.yaw) - from.yaw, angle_steps));
    e.motion_ticks = static_cast<std::uint8_t>(t);
}

} // namespace

QuantizedPose predict(const FrameEntity& base, std::uint64_t ticks, std::uint32_t angle_steps) {
    return predicted(base, ticks, angle_steps);
}

void set_motion(FrameEntity& e, const QuantizedPose& from, std::uint64_t ticks,
                std::uint32_t angle_steps) {
    measure_motion(e, from, ticks, angle_steps);
}

// --- frame ring ---

DeltaFrame& FrameRing::start(std::uint64_t tick) {
    if (!spare_.empty()) {
        next_.entities.swap(spare_.back());
        if (spare_.back().capacity() == 0) {
            spare_.pop_back();
        }
    }
    next_.tick = tick;
    next_.entities.clear();
    // Without reusable memory (the acknowledgements came late, so nothing was forgotten)
    // room for the newest frame at once: a buffer grown from nothing went through every
    // power of two, ten allocations and copies for a frame of 500 entities, and its
    // 16 and 32 KiB steps, freed again ticks later, were most of what the allocator kept
    // resident in a 500-client soak.
    if (next_.entities.capacity() == 0) {
        next_.entities.reserve(newest_size_ + kSlackEntities);
    }
    return next_;
}

void FrameRing::commit() {
    newest_size_ = next_.entities.size();
    if (oversized(next_.entities.capacity())) {
        next_.entities.shrink_to_fit(); // built in a buffer once needed for a larger set
    }
    Slot& s = slots_[next_.tick % kAckedHistory];
    if (s.used) {
        keep_spare(std::move(s.frame.entities), false); // last used kAckedHistory ticks ago
    }
    s.frame.tick = next_.tick;
    s.frame.entities = std::move(next_.entities);
    s.used = true;
    next_.entities = {};
}

void FrameRing::forget_older_than(std::uint64_t tick) {
    std::array<Slot*, kAckedHistory> old{};
    std::size_t count = 0;
    for (Slot& s : slots_) {
        if (s.used && s.frame.tick < tick) {
            old[count++] = &s;
        }
    }
    // The newest last, so that it is the first reused.
    std::sort(old.begin(), old.begin() + static_cast<std::ptrdiff_t>(count),
              [](const Slot* a, const Slot* b) { return a->frame.tick < b->frame.tick; });
    for (std::size_t k = 0; k < count; ++k) {
        old[k]->used = false;
        keep_spare(std::move(old[k]->frame.entities), true);
        old[k]->frame.entities = {};
    }
}

void FrameRing::keep_spare(std::vector<FrameEntity>&& memory, bool warm) {
    if (memory.capacity() == 0 || oversized(memory.capacity())) {
        return; // nothing to reuse (must not push a buffer that has memory out), or too much
    }
    memory.clear();
    if (warm) {
        spare_.push_back(std::move(memory));
    } else {
        spare_.insert(spare_.begin(), std::move(memory));
    }
    if (spare_.size() > kMaxSpare) {
        spare_.erase(spare_.begin());
    }
}

std::size_t FrameRing::capacity() const {
    std::size_t entities = next_.entities.capacity();
    for (const Slot& s : slots_) {
        entities += s.frame.entities.capacity();
    }
    for (const std::vector<FrameEntity>& memory : spare_) {
        entities += memory.capacity();
    }
    return entities;
}

// --- encoder ---

void AckedSnapshotEncoder::begin(std::uint64_t tick, std::optional<std::uint64_t> acked,
                                 pb::Snapshot& out, UpdateColumns* columns) {
    clear_to_need(out);
    out.set_server_tick(tick);
    columns_ = columns;
    if (columns_ != nullptr) {
        columns_->clear();
    }
    base_ = nullptr;
    if (acked && *acked < tick) {
        // The caller's acknowledgements never go back: no later snapshot is coded against
        // an older frame.
        frames_.forget_older_than(*acked);
        base_ = tick - *acked < kAckedHistory ? frames_.find(*acked) : nullptr;
    }
    next_ = &frames_.start(tick);
    if (base_ != nullptr) {
        out.set_baseline_tick(base_->tick);
        ticks_since_base_ = tick - base_->tick;
    }
    base_at_ = 0;
    last_entry_id_ = 0;
    counts_ = {};
    counts_.coded_against_baseline = base_ != nullptr;
    counts_.baseline_age = base_ != nullptr ? ticks_since_base_ : 0;
}

void AckedSnapshotEncoder::leave_baseline_below(std::uint32_t id, pb::Snapshot& out) {
    if (base_ == nullptr) {
        return;
    }
    const std::vector<FrameEntity>& base = base_->entities;
    for (; base_at_ < base.size() && base[base_at_].id < id; ++base_at_) {
        out.add_leave(base[base_at_].id);
        ++counts_.leaves;
    }
}

bool AckedSnapshotEncoder::meets_baseline(std::uint32_t id, pb::Snapshot& out) {
    if (base_ == nullptr) {
        return false;
    }
    const std::vector<FrameEntity>& base = base_->entities;
    // The call only when there is something to leave (most entities stay known).
    if (base_at_ < base.size() && base[base_at_].id < id) {
        leave_baseline_below(id, out);
    }
    return base_at_ < base.size() && base[base_at_].id == id;
}

void AckedSnapshotEncoder::write_entry(std::uint32_t id, std::uint32_t fields,
                                       const std::int32_t* values, std::size_t count,
                                       pb::Snapshot& out) {
    const std::uint32_t id_step = counts_.entries == 0 ? id : id - last_entry_id_;
    if (columns_ != nullptr) {
        columns_->add(id_step, fields, std::span<const std::int32_t>(values, count));
    } else {
        out.add_update_head(update_head(id_step, fields));
        if (mask_apart(fields)) {
            out.add_update_fields(fields);
        }
        for (std::size_t k = 0; k < count; ++k) {
            out.add_update_values(values[k]);
        }
    }
    last_entry_id_ = id;
    ++counts_.entries;
}

void AckedSnapshotEncoder::add(std::uint32_t id, const QuantizedPose& pose, std::uint8_t tier,
                               std::uint32_t kind, const std::array<float, 3>& half_extents,
                               pb::Snapshot& out) {
    if (!carry(id, pose, tier, out)) {
        enter(id, pose, tier, kind, half_extents, out);
    }
}

void AckedSnapshotEncoder::enter(std::uint32_t id, const QuantizedPose& pose, std::uint8_t tier,
                                 std::uint32_t kind, const std::array<float, 3>& half_extents,
                                 pb::Snapshot& out) {
    leave_baseline_below(id, out);
    assert(base_ == nullptr || base_at_ == base_->entities.size() ||
           base_->entities[base_at_].id != id);
    FrameEntity& n = next_->entities.emplace_back();
    n.pose = pose;
    n.id = id;
    n.kind = kind;
    n.half_extents = write_enter(id, pose, tier, half_extents, kind, settings_, out);
    n.tier = tier;
    n.enter_tier = tier;
    ++counts_.enters;
}

bool AckedSnapshotEncoder::carry(std::uint32_t id, const QuantizedPose& pose, std::uint8_t tier,
                                 pb::Snapshot& out) {
    if (!meets_baseline(id, out)) {
        return false;
    }
    // Each entity is written once, in place: a frame is rewritten for every client every
    // tick, so its copies are a large part of the encoder's cost.
    const FrameEntity& b = base_->entities[base_at_++]; // in the ring, not in next_
    FrameEntity& n = next_->entities.emplace_back(b);
    // Ticks since b's pose was set: the prediction's span, the due rule's start.
    const std::uint64_t t = ticks_since_base_ + b.held_ticks;
    const bool due = due_since(id, b.tier, next_->tick - t, next_->tick);
    if (tier == b.tier && !due) {
        n.held_ticks = static_cast<std::uint8_t>(t); // held as it is: both ends copy it
        return true;
    }
    n.held_ticks = 0;
    const std::uint32_t steps = settings_.angle_steps;
    const QuantizedPose expected = predicted(b, t, steps);
    const std::int64_t rx = static_cast<std::int64_t>(pose.x) - expected.x;
    const std::int64_t ry = static_cast<std::int64_t>(pose.y) - expected.y;
    const std::int64_t rz = static_cast<std::int64_t>(pose.z) - expected.z;
    const std::int64_t rpitch = static_cast<std::int64_t>(pose.pitch) - b.pose.pitch;
    const bool fits = fits_int32(rx) && fits_int32(ry) && fits_int32(rz) && fits_int32(rpitch);
    if (tier != b.tier || !fits) {
        const std::array<std::int32_t, 6> values{tier,   pose.x,   pose.y,
                                                 pose.z, pose.yaw, pose.pitch};
        write_entry(id, kFieldRebase, values.data(), values.size(), out);
        n.pose = pose;
        n.tier = tier;
        clear_motion(n);
    } else {
        std::array<std::int32_t, 5> values{};
        std::size_t count = 0;
        std::uint32_t fields = 0;
        const auto field = [&](std::uint32_t bit, std::int64_t value) {
            if (value != 0) {
                values[count++] = static_cast<std::int32_t>(value);
                fields |= bit;
            }
        };
        field(kFieldX, rx);
        field(kFieldY, ry);
        field(kFieldZ, rz);
        field(kFieldYaw,
              wrap_angle_delta(static_cast<std::int64_t>(pose.yaw) - expected.yaw, steps));
        field(kFieldPitch, rpitch);
        if (fields != 0) {
            write_entry(id, fields, values.data(), count, out);
        }
        n.pose = pose;
        measure_motion(n, b.pose, t, steps);
    }
    counts_.moved += same_position(n.pose, b.pose) ? 0 : 1;
    return true;
}

bool AckedSnapshotEncoder::carry_unwritten(std::uint32_t id, pb::Snapshot& out) {
    if (!meets_baseline(id, out)) {
        return false;
    }
    const FrameEntity& b = base_->entities[base_at_++];
    FrameEntity& n = next_->entities.emplace_back(b);
    const std::uint64_t t = ticks_since_base_ + b.held_ticks;
    if (!due_since(id, b.tier, next_->tick - t, next_->tick)) {
        n.held_ticks = static_cast<std::uint8_t>(t); // as carry(): both ends copy it
        return true;
    }
    // What the decoder makes of a due entity without an entry: its prediction, on the
    // tier it had. (Through the functions, not inlined here: a third inlined copy made the
    // compiler take the velocity's helper out of line in the decoder's loop.)
    const std::uint32_t steps = settings_.angle_steps;
    n.held_ticks = 0;
    n.pose = predict(b, t, steps);
    set_motion(n, b.pose, t, steps);
    counts_.moved += same_position(n.pose, b.pose) ? 0 : 1;
    return true;
}

void AckedSnapshotEncoder::leave_the_rest(pb::Snapshot& out) {
    for (; base_ != nullptr && base_at_ < base_->entities.size(); ++base_at_) {
        out.add_leave(base_->entities[base_at_].id);
        ++counts_.leaves;
    }
}

void AckedSnapshotEncoder::restart(pb::Snapshot& out, bool against_nothing) {
    assert(next_ != nullptr);
    const std::uint64_t tick = next_->tick;
    out.Clear();
    out.set_server_tick(tick);
    if (columns_ != nullptr) {
        columns_->clear();
    }
    if (against_nothing) {
        base_ = nullptr;
    }
    if (base_ != nullptr) {
        out.set_baseline_tick(base_->tick);
    }
    next_->entities.clear();
    base_at_ = 0;
    last_entry_id_ = 0;
    counts_ = {};
    counts_.coded_against_baseline = base_ != nullptr;
    counts_.baseline_age = base_ != nullptr ? ticks_since_base_ : 0;
}

AckedSnapshotCounts AckedSnapshotEncoder::finish(pb::Snapshot& out) {
    leave_the_rest(out);
    base_ = nullptr; // its slot may be the one the new frame takes
    next_ = nullptr;
    frames_.commit();
    return counts_;
}

// --- decoder ---

namespace {

/// `b` carried to the new frame of `tick` through its update entry `e` (nullptr: none),
/// `ticks` after its frame; a problem when the entry does not fit the entity.
std::optional<SnapshotProblem> carry(const FrameEntity& b, const UpdateEntry* e,
                                     const pb::Snapshot& s, std::uint64_t tick, std::uint64_t ticks,
                                     std::uint32_t steps, FrameEntity& n) {
    n = b;
    const std::uint64_t t = ticks + b.held_ticks; // since b's pose was set
    const bool due = due_since(b.id, b.tier, tick - t, tick);
    const auto where = [&] { return "the update entry of " + entity_name(b.id); };
    if (e != nullptr && e->fields == kFieldRebase) {
        const std::int32_t* values = s.update_values().data() + e->at;
        if (auto problem = rebase_problem(values, steps, where)) {
            return problem;
        }
        n.tier = static_cast<std::uint8_t>(values[0]);
        n.pose = {values[1], values[2], values[3], values[4], values[5]};
        n.held_ticks = 0;
        clear_motion(n);
        return std::nullopt;
    }
    if (!due) {
        if (e != nullptr) {
            return SnapshotProblem{"malformed_update",
                                   where() + ": tier " + std::to_string(b.tier) +
                                       " is not due at tick " + std::to_string(tick)};
        }
        n.held_ticks = static_cast<std::uint8_t>(t);
        return std::nullopt;
    }
    n.held_ticks = 0;
    const QuantizedPose expected = predicted(b, t, steps);
    if (e == nullptr) {
        n.pose = expected;
        measure_motion(n, b.pose, t, steps);
        return std::nullopt;
    }
    const std::int32_t* values = s.update_values().data() + e->at;
    if (b.tier == kHeardTier && (e->fields & (kFieldYaw | kFieldPitch)) != 0) {
        return SnapshotProblem{"angles_on_heard_tier",
                               where() + ": view angles for a heard-only entity"};
    }
    int k = 0;
    bool in_range = true;
    const auto add = [&](std::uint32_t bit, std::int32_t from, std::int32_t& to) {
        to = from;
        if ((e->fields & bit) == 0) {
            return;
        }
        const std::int64_t sum = static_cast<std::int64_t>(from) + values[k++];
        in_range = in_range && sum >= -kMaxQuantizedCoordinate && sum <= kMaxQuantizedCoordinate;
        to = static_cast<std::int32_t>(
            std::clamp<std::int64_t>(sum, -kMaxQuantizedCoordinate, kMaxQuantizedCoordinate));
    };
    add(kFieldX, expected.x, n.pose.x);
    add(kFieldY, expected.y, n.pose.y);
    add(kFieldZ, expected.z, n.pose.z);
    n.pose.yaw = (e->fields & kFieldYaw) != 0 ? add_angle_steps(expected.yaw, values[k++], steps)
                                              : expected.yaw;
    add(kFieldPitch, b.pose.pitch, n.pose.pitch);
    if (!in_range) {
        return SnapshotProblem{"malformed_update", where() + ": a value leaves the range"};
    }
    // Only a pitch that arrives: one held from the baseline was checked when it came.
    if ((e->fields & kFieldPitch) != 0 && pitch_beyond(n.pose.pitch, steps)) {
        return SnapshotProblem{"malformed_update",
                               where() + ": " + pitch_beyond_detail(n.pose.pitch, steps)};
    }
    measure_motion(n, b.pose, t, steps);
    return std::nullopt;
}

FrameEntity entered(const pb::EntityState& e) {
    FrameEntity n;
    n.pose = {e.x(), e.y(), e.z(), static_cast<std::int32_t>(e.yaw()), e.pitch()};
    n.id = e.id();
    n.kind = e.kind();
    n.half_extents = {e.half_x(), e.half_y(), e.half_z()};
    n.tier = static_cast<std::uint8_t>(e.tier());
    n.enter_tier = n.tier;
    return n;
}

} // namespace

std::vector<SnapshotProblem> AckedSnapshotDecoder::apply(const pb::Snapshot& s) {
    std::vector<SnapshotProblem> problems;
    const std::uint64_t tick = s.server_tick();
    if (newest_tick_ && tick <= *newest_tick_) {
        problems.push_back({"stale_snapshot", "tick " + std::to_string(tick) +
                                                  " is not newer than the newest applied, " +
                                                  std::to_string(*newest_tick_)});
        return problems;
    }
    static const DeltaFrame kNothing;
    const DeltaFrame* base = &kNothing;
    std::uint64_t ticks = 0;
    if (s.has_baseline_tick()) {
        const std::uint64_t from = s.baseline_tick();
        base = from < tick && tick - from < kAckedHistory ? frames_.find(from) : nullptr;
        if (base == nullptr) {
            problems.push_back({"baseline_missing",
                                "tick " + std::to_string(tick) + " is coded against tick " +
                                    std::to_string(from) + ", which this client does not hold"});
            return problems;
        }
        ticks = tick - from;
    }
    std::vector<UpdateEntry>& entries = entries_;
    if (auto problem = read_update_entries(s, entries)) {
        problems.push_back(std::move(*problem));
        return problems;
    }
    for (const pb::EntityState& e : s.enter()) {
        if (auto problem = enter_problem(e, settings_.angle_steps)) {
            problems.push_back(std::move(*problem));
        }
    }
    const auto& enters = s.enter();
    const auto& leaves = s.leave();
    for (int i = 1; i < enters.size(); ++i) {
        if (enters[i].id() <= enters[i - 1].id()) {
            problems.push_back({"malformed_update",
                                "enter ids must increase (" + entity_name(enters[i].id()) + ")"});
        }
    }
    for (int i = 1; i < leaves.size(); ++i) {
        if (leaves[i] <= leaves[i - 1]) {
            problems.push_back(
                {"malformed_update", "leave ids must increase (" + entity_name(leaves[i]) + ")"});
        }
    }
    if (!problems.empty()) {
        return problems;
    }

    // The baseline's entities in id order, each dropped (a leave), carried (through its
    // entry, if any), with the entering ones between them; every enter, leave and entry
    // must meet exactly what the baseline says.
    DeltaFrame& next = frames_.start(tick);
    int enter_at = 0;
    int leave_at = 0;
    std::size_t entry_at = 0;
    const auto take_enters_below = [&](std::uint64_t id) {
        for (; enter_at < enters.size() && enters[enter_at].id() < id; ++enter_at) {
            next.entities.push_back(entered(enters[enter_at]));
        }
    };
    for (const FrameEntity& b : base->entities) {
        take_enters_below(b.id);
        if (enter_at < enters.size() && enters[enter_at].id() == b.id) {
            problems.push_back({"duplicate_enter", entity_name(b.id) + " entered while known"});
            return problems;
        }
        if (leave_at < leaves.size() && leaves[leave_at] < b.id) {
            break; // a leave of an entity the baseline lacks: reported below
        }
        if (entry_at < entries.size() && entries[entry_at].id < b.id) {
            break; // an entry for an entity the baseline lacks: reported below
        }
        const bool leaves_now = leave_at < leaves.size() && leaves[leave_at] == b.id;
        const UpdateEntry* entry = entry_at < entries.size() && entries[entry_at].id == b.id
                                       ? &entries[entry_at]
                                       : nullptr;
        if (leaves_now) {
            ++leave_at;
            if (entry != nullptr) {
                break; // an entry for an entity that leaves: reported below
            }
            continue;
        }
        entry_at += entry != nullptr ? 1 : 0;
        // In place (the next frame is rebuilt from scratch by every apply(), so a rejected
        // snapshot leaves nothing behind that matters).
        FrameEntity& n = next.entities.emplace_back();
        if (auto problem = carry(b, entry, s, tick, ticks, settings_.angle_steps, n)) {
            problems.push_back(std::move(*problem));
            return problems;
        }
    }
    take_enters_below(std::uint64_t{1} << 32);
    if (leave_at < leaves.size()) {
        problems.push_back(
            {"leave_for_unknown_entity", entity_name(leaves[leave_at]) + " left while unknown"});
    }
    if (entry_at < entries.size()) {
        problems.push_back({"update_for_unknown_entity", "the update entry of " +
                                                             entity_name(entries[entry_at].id) +
                                                             ": the entity is not known"});
    }
    if (!problems.empty()) {
        return problems;
    }
    frames_.commit();
    newest_tick_ = tick;
    if (s.has_baseline_tick()) {
        // A server's baselines never go back (docs/protocol.md): every snapshot still to
        // apply is coded against this one's baseline or a newer frame, or against nothing.
        frames_.forget_older_than(s.baseline_tick());
    }
    return problems;
}

const FrameEntity* AckedSnapshotDecoder::find(std::uint32_t id) const {
    const DeltaFrame* frame = newest();
    if (frame == nullptr) {
        return nullptr;
    }
    const auto it =
        std::lower_bound(frame->entities.begin(), frame->entities.end(), id,
                         [](const FrameEntity& e, std::uint32_t wanted) { return e.id < wanted; });
    return it != frame->entities.end() && it->id == id ? &*it : nullptr;
}

std::optional<Pose> AckedSnapshotDecoder::pose(std::uint32_t id) const {
    const FrameEntity* e = find(id);
    if (e == nullptr) {
        return std::nullopt;
    }
    const QuantizedPose now =
        e->held_ticks == 0 ? e->pose : predicted(*e, e->held_ticks, settings_.angle_steps);
    return dequantize(now, settings_.quantum(e->tier), settings_.angle_steps);
}

std::vector<SnapshotProblem> AckedSnapshotDecoder::check_audit(const pb::Snapshot& snapshot,
                                                               double& max_error) const {
    std::vector<SnapshotProblem> problems;
    max_error = 0.0;
    for (const pb::AuditPose& a : snapshot.audit()) {
        const FrameEntity* known = find(a.id());
        check_audit_pose(a, known != nullptr ? &known->pose : nullptr,
                         known != nullptr ? known->tier : 0, settings_, max_error, problems);
    }
    return problems;
}

} // namespace dsoc::protocol
