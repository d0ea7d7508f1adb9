#include "dsoc/server/replication_state.hpp"

#include "dsoc/protocol/datagram.hpp"
#include "dsoc/protocol/interest_merge.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include <algorithm>
#include <cassert>
#include <limits>

namespace dsoc::server {

namespace {

/// How many entities ahead build_snapshot() asks for the encoder's remembered pose:
/// 500 clients' poses do not stay in cache from one tick to the next.
constexpr std::size_t kPrefetchAhead = 8;

using google::protobuf::io::CodedOutputStream;

// What the parts of an acknowledged-delta snapshot take on the wire at most, for the cheap
// check that a snapshot fits its datagrams (protocol::kMaxSnapshotBytes). [Units: bytes]
constexpr std::size_t kMaxVarint32Bytes = 5;
/// An enter: its field's tag and length (below 128), then EntityState's eleven fields,
/// each a 1-byte tag and a varint.
constexpr std::size_t kMaxEnterBytes = 2 + 11 * (1 + kMaxVarint32Bytes);
/// An update entry: its head (an id step below 2^32 shifted by four bits: 6 bytes), the
/// mask apart and six values.
constexpr std::size_t kMaxEntryBytes =
    6 + kMaxVarint32Bytes + protocol::UpdateColumns::kMaxValuesPerEntry * kMaxVarint32Bytes;
static_assert(kMaxEntryBytes <= kMaxEnterBytes);
/// An audit pose: its field's tag and length, the id and five floats.
constexpr std::size_t kMaxAuditBytes = 2 + (1 + kMaxVarint32Bytes) + 5 * (1 + 4);
/// The envelope's tag and length (of a snapshot below 2^21 bytes), the tick and the
/// baseline tick (a tag and a 64-bit varint each), the tags and lengths of the packed
/// fields (leave and the three update columns).
constexpr std::size_t kMaxFixedBytes = (1 + 3) + 2 * (1 + 10) + 4 * (1 + 3);
static_assert(protocol::kMaxSnapshotBytes < (std::size_t{1} << 21));

/// The bytes of the envelope holding a snapshot of `body` bytes (snapshot_frame()'s).
std::size_t envelope_bytes(std::size_t body) {
    return 1 + CodedOutputStream::VarintSize32(static_cast<std::uint32_t>(body)) + body;
}

/// The bytes of a snapshot's body: its fields, `columns` (when given) its update columns.
std::size_t body_bytes(const protocol::pb::Snapshot& snapshot,
                       const protocol::UpdateColumns* columns) {
    return snapshot.ByteSizeLong() + (columns != nullptr ? columns->wire_bytes() : 0);
}

/// Whether the envelope of `snapshot` (whole: its leaves written) fits its datagrams:
/// first by a bound from its counts (the usual case: a few hundred entities), else exactly.
bool fits(const protocol::pb::Snapshot& snapshot, const protocol::UpdateColumns* columns,
          const protocol::AckedSnapshotCounts& counts) {
    const std::size_t columns_bytes =
        columns != nullptr ? columns->wire_bytes() : protocol::update_column_bytes(snapshot);
    const std::size_t most = kMaxFixedBytes + counts.enters * kMaxEnterBytes +
                             counts.leaves * kMaxVarint32Bytes + columns_bytes +
                             static_cast<std::size_t>(snapshot.audit_size()) * kMaxAuditBytes;
    return most <= protocol::kMaxSnapshotBytes ||
           envelope_bytes(body_bytes(snapshot, columns)) <= protocol::kMaxSnapshotBytes;
}

/// Bytes of a packed field of `payload` bytes (fields 4-7: a 1-byte tag); none when empty.
std::size_t packed_bytes(std::size_t payload) {
    return payload == 0
               ? 0
               : 1 + CodedOutputStream::VarintSize32(static_cast<std::uint32_t>(payload)) + payload;
}

/// Bytes of a repeated message's element of `size` bytes: tag, length, the message.
std::size_t element_bytes(std::size_t size) {
    return 1 + CodedOutputStream::VarintSize32(static_cast<std::uint32_t>(size)) + size;
}

/// What one wanted entity takes in a snapshot that may not fit (build_measured()).
enum class Part : std::uint8_t {
    held,    ///< carried, not due: nothing written
    current, ///< carried, due, at its prediction: nothing written
    entry,   ///< carried with an update entry: may be deferred
    enter,   ///< enters: may be deferred
    capped,  ///< would enter, but over protocol::kMaxEntersPerSnapshot: deferred
};

struct Measured {
    std::uint32_t id = 0;
    /// Its place in the order entries and enters are given room (0 first); the others:
    /// kNoRank.
    std::uint32_t rank = 0;
    float distance2 = 0.0f;       ///< from the eye, squared [world units^2]
    std::uint32_t bytes = 0;      ///< an entry's values; an enter's element (tag, length, message)
    std::uint32_t mask_bytes = 0; ///< an entry's mask apart (0: in its head)
    std::uint16_t waited = 0;     ///< snapshots in a row it was deferred before this one
    Part part = Part::held;
    std::uint8_t tier = 0;
};
constexpr std::uint32_t kNoRank = std::numeric_limits<std::uint32_t>::max();

/// build_measured()'s scratch, one per thread (a client's snapshot is built on one).
struct MeasureScratch {
    std::vector<Measured> parts;      ///< one per wanted entity in the world, in id order
    std::vector<std::uint32_t> order; ///< indexes into parts of the entries and enters
};
MeasureScratch& measure_scratch() {
    thread_local MeasureScratch scratch;
    return scratch;
}

void add_audit(const interest::Entity& e, protocol::pb::Snapshot& snapshot) {
    protocol::pb::AuditPose& a = *snapshot.add_audit();
    a.set_id(e.id);
    a.set_x(e.move.position.x);
    a.set_y(e.move.position.y);
    a.set_z(e.move.position.z);
    a.set_yaw(e.yaw_deg);
    a.set_pitch(e.pitch_deg);
}

} // namespace

protocol::Pose pose_of(const interest::Entity& e) {
    return {e.move.position.x, e.move.position.y, e.move.position.z, e.yaw_deg, e.pitch_deg};
}

void SharedPoses::compute(const interest::GameWorld& world,
                          const protocol::QuantizationSettings& quantization) {
    quantization_ = quantization;
    poses_.clear();
    ids_.clear();
    for (const interest::Entity& e : world.entities()) {
        ids_.push_back(e.id);
        const protocol::Pose pose = pose_of(e);
        for (std::uint8_t tier = 0; tier < protocol::kTiers; ++tier) {
            poses_.push_back(protocol::quantize(pose, quantization, tier));
        }
    }
}

void ReplicationState::build_snapshot(const interest::GameWorld& world,
                                      std::span<const interest::Interest> interest,
                                      std::uint64_t tick, bool audit,
                                      protocol::pb::Snapshot& snapshot, const SharedPoses* poses,
                                      protocol::UpdateColumns* columns) {
    assert(poses == nullptr ||
           (poses->size() == world.entities().size() &&
            poses->quantization().angle_steps == encoder_.settings().angle_steps &&
            poses->quantization().position_quantum == encoder_.settings().position_quantum &&
            poses->quantization().heard_quantum == encoder_.settings().heard_quantum));
    encoder_.begin(tick, snapshot, columns);
    next_known_.clear();

    // Merge two increasing id lists (protocol::merge_interest): old knowledge and the
    // new interest set. The world's entities are in increasing id order too, so each wanted entity
    // is found by walking forward (no per-entity lookup: this loop runs for every entity of every
    // client every tick), over the tick's side-by-side ids when there are shared poses.
    const std::vector<interest::Entity>& entities = world.entities();
    const std::uint32_t* ids = poses != nullptr ? poses->ids().data() : nullptr;
    std::size_t next_entity = 0;
    const auto id_at = [&](std::size_t k) { return ids != nullptr ? ids[k] : entities[k].id; };
    const auto find_entity = [&](std::uint32_t id) -> const interest::Entity* {
        while (next_entity < entities.size() && id_at(next_entity) < id) {
            ++next_entity;
        }
        return next_entity < entities.size() && id_at(next_entity) == id ? &entities[next_entity]
                                                                         : nullptr;
    };
    const auto leave = [&](std::uint32_t id) { // no longer of interest (or gone from the world)
        encoder_.leave(id, snapshot);
    };
    const auto send = [&](std::size_t j, bool was_known) {
        const interest::Interest wanted = interest[j];
        if (j + kPrefetchAhead < interest.size()) {
            encoder_.prefetch(interest[j + kPrefetchAhead].id);
        }
        const interest::Entity* e = find_entity(wanted.id);
        if (e == nullptr) { // contract breach: never leave a stale id known
            if (was_known) {
                encoder_.leave(wanted.id, snapshot);
            }
            return;
        }
        next_known_.push_back(wanted.id);
        if (!was_known) {
            const glm::vec3 half = world.box_of(*e).half_extents();
            encoder_.enter(wanted.id, pose_of(*e), {half.x, half.y, half.z},
                           static_cast<std::uint32_t>(e->kind), wanted.tier, snapshot);
        } else {
            if (!protocol::due_at(wanted.id, wanted.tier, tick)) {
                return; // deferred: this coarse-tier entity is not due this tick
            }
            if (poses != nullptr) {
                encoder_.update_quantized(wanted.id, poses->at(next_entity, wanted.tier),
                                          wanted.tier, snapshot);
            } else {
                encoder_.update(wanted.id, pose_of(*e), wanted.tier, snapshot);
            }
        }
        if (audit && wanted.tier != protocol::kHeardTier) { // never the pose hearing withholds
            add_audit(*e, snapshot);
        }
    };
    protocol::merge_interest(
        known_, interest, [](const interest::Interest& w) { return w.id; }, leave, send);
    known_.swap(next_known_);
    last_updates_ = static_cast<std::size_t>(snapshot.enter_size()) +
                    (columns != nullptr ? columns->count() : snapshot.update_head_size());
}

void ReplicationState::choose_enters(const interest::GameWorld& world,
                                     std::span<const interest::Interest> interest, glm::vec3 eye,
                                     const protocol::DeltaFrame* baseline) {
    enter_allowed_.clear();
    if (interest.size() <= protocol::kMaxEntersPerSnapshot) {
        return; // fewer wanted than may enter: no choice to make (the usual case)
    }
    // The entities the baseline lacks (both lists in increasing id order).
    candidates_.clear();
    const std::vector<interest::Entity>& entities = world.entities();
    std::size_t at_base = 0;
    std::size_t at_world = 0;
    for (std::size_t i = 0; i < interest.size(); ++i) {
        const std::uint32_t id = interest[i].id;
        if (baseline != nullptr) {
            while (at_base < baseline->entities.size() && baseline->entities[at_base].id < id) {
                ++at_base;
            }
            if (at_base < baseline->entities.size() && baseline->entities[at_base].id == id) {
                continue; // carried, not entered
            }
        }
        while (at_world < entities.size() && entities[at_world].id < id) {
            ++at_world;
        }
        const glm::vec3 d = at_world < entities.size() && entities[at_world].id == id
                                ? entities[at_world].move.position - eye
                                : glm::vec3(0.0f); // not in the world: skipped when built
        candidates_.push_back(
            {interest[i].tier, d.x * d.x + d.y * d.y + d.z * d.z, static_cast<std::uint32_t>(i)});
    }
    if (candidates_.size() <= protocol::kMaxEntersPerSnapshot) {
        return;
    }
    const auto first = [](const EnterCandidate& a, const EnterCandidate& b) {
        return a.tier != b.tier             ? a.tier < b.tier
               : a.distance2 != b.distance2 ? a.distance2 < b.distance2
                                            : a.index < b.index;
    };
    const auto cut =
        candidates_.begin() + static_cast<std::ptrdiff_t>(protocol::kMaxEntersPerSnapshot);
    std::nth_element(candidates_.begin(), cut, candidates_.end(), first);
    enter_allowed_.assign(interest.size(), 1);
    for (auto it = cut; it != candidates_.end(); ++it) {
        enter_allowed_[it->index] = 0;
    }
}

void ReplicationState::build_acked_snapshot(
    const interest::GameWorld& world, std::span<const interest::Interest> interest, glm::vec3 eye,
    std::uint64_t tick, std::optional<std::uint64_t> acked_tick, bool audit,
    protocol::pb::Snapshot& snapshot, const SharedPoses* poses, protocol::UpdateColumns* columns) {
    assert(acked_encoder_ != nullptr);
    protocol::AckedSnapshotEncoder& encoder = *acked_encoder_;
    encoder.begin(tick, acked_tick, snapshot, columns);
    choose_enters(world, interest, eye, encoder.baseline());
    known_.clear();
    last_deferred_ = 0;
    last_updates_deferred_ = 0;
    if (measure_first_) {
        // The last snapshot did not fit: this one most likely does not either, and the
        // measured build needs no first try.
        build_measured(world, interest, eye, audit, snapshot, poses, columns);
        last_acked_ = encoder.finish(snapshot);
        last_updates_ = last_acked_.enters + last_acked_.entries;
        assert(envelope_bytes(body_bytes(snapshot, columns)) <= protocol::kMaxSnapshotBytes);
        return;
    }
    const std::vector<interest::Entity>& entities = world.entities();
    const std::uint32_t* ids = poses != nullptr ? poses->ids().data() : nullptr;
    std::size_t next_entity = 0;
    const auto id_at = [&](std::size_t k) { return ids != nullptr ? ids[k] : entities[k].id; };
    for (std::size_t i = 0; i < interest.size(); ++i) { // increasing ids, as the world's
        const interest::Interest& wanted = interest[i];
        while (next_entity < entities.size() && id_at(next_entity) < wanted.id) {
            ++next_entity;
        }
        if (next_entity == entities.size() || id_at(next_entity) != wanted.id) {
            continue; // contract breach: not in the world, so not known either
        }
        const interest::Entity& e = entities[next_entity];
        const protocol::QuantizedPose pose =
            poses != nullptr ? poses->at(next_entity, wanted.tier)
                             : protocol::quantize(pose_of(e), encoder.settings(), wanted.tier);
        if (!encoder.carry(wanted.id, pose, wanted.tier, snapshot)) {
            if (!enter_allowed_.empty() && enter_allowed_[i] == 0) {
                ++last_deferred_; // no room this snapshot: it enters in a later one
                continue;
            }
            const glm::vec3 half = world.box_of(e).half_extents();
            encoder.enter(wanted.id, pose, wanted.tier, static_cast<std::uint32_t>(e.kind),
                          {half.x, half.y, half.z}, snapshot);
        }
        known_.push_back(wanted.id);
        if (audit && wanted.tier == 0) {
            add_audit(e, snapshot);
        }
    }
    encoder.leave_the_rest(snapshot);
    if (fits(snapshot, columns, encoder.counts())) {
        waiting_.clear(); // nothing left out
    } else {
        build_measured(world, interest, eye, audit, snapshot, poses, columns);
    }
    last_acked_ = encoder.finish(snapshot);
    last_updates_ = last_acked_.enters + last_acked_.entries;
    assert(envelope_bytes(body_bytes(snapshot, columns)) <= protocol::kMaxSnapshotBytes);
}

void ReplicationState::build_measured(const interest::GameWorld& world,
                                      std::span<const interest::Interest> interest, glm::vec3 eye,
                                      bool audit, protocol::pb::Snapshot& snapshot,
                                      const SharedPoses* poses, protocol::UpdateColumns* columns) {
    // The snapshot is written (again), measuring what each entity takes; unless it fits, the
    // entries and enters are ranked (as choose_enters(), those waiting long first), the
    // most of them that fit found, and the snapshot written once more with those alone.
    protocol::AckedSnapshotEncoder& encoder = *acked_encoder_;
    MeasureScratch& scratch = measure_scratch();
    std::vector<Measured>& parts = scratch.parts;
    const std::vector<interest::Entity>& entities = world.entities();
    const std::uint32_t* ids = poses != nullptr ? poses->ids().data() : nullptr;
    const auto id_at = [&](std::size_t k) { return ids != nullptr ? ids[k] : entities[k].id; };
    // `f(i, k)` for each wanted entity interest[i] that is in the world, entities[k].
    const auto each_wanted = [&](auto&& f) {
        std::size_t next_entity = 0;
        for (std::size_t i = 0; i < interest.size(); ++i) {
            while (next_entity < entities.size() && id_at(next_entity) < interest[i].id) {
                ++next_entity;
            }
            if (next_entity < entities.size() && id_at(next_entity) == interest[i].id) {
                f(i, next_entity);
            }
        }
    };
    const auto pose_at = [&](std::size_t k, std::uint8_t tier) {
        return poses != nullptr
                   ? poses->at(k, tier)
                   : protocol::quantize(pose_of(entities[k]), encoder.settings(), tier);
    };
    const auto enter = [&](const interest::Interest& wanted, std::size_t k) {
        const interest::Entity& e = entities[k];
        const glm::vec3 half = world.box_of(e).half_extents();
        encoder.enter(wanted.id, pose_at(k, wanted.tier), wanted.tier,
                      static_cast<std::uint32_t>(e.kind), {half.x, half.y, half.z}, snapshot);
    };
    // The bytes of the masks apart and of the values written so far.
    int masks_seen = 0;
    int values_seen = 0;
    std::size_t masks_written = 0;
    std::size_t values_written = 0;
    const auto column_bytes = [&]() -> std::pair<std::size_t, std::size_t> {
        if (columns != nullptr) {
            return {columns->mask_bytes(), columns->value_bytes()};
        }
        for (; masks_seen < snapshot.update_fields_size(); ++masks_seen) {
            masks_written += CodedOutputStream::VarintSize32(snapshot.update_fields(masks_seen));
        }
        for (; values_seen < snapshot.update_values_size(); ++values_seen) {
            values_written += CodedOutputStream::VarintSize32(
                google::protobuf::internal::WireFormatLite::ZigZagEncode32(
                    snapshot.update_values(values_seen)));
        }
        return {masks_written, values_written};
    };
    const auto measure = [&] {
        parts.clear();
        known_.clear();
        last_deferred_ = 0;
        masks_seen = 0;
        values_seen = 0;
        masks_written = 0;
        values_written = 0;
        std::size_t at_waiting = 0;
        each_wanted([&](std::size_t i, std::size_t k) {
            const interest::Interest& wanted = interest[i];
            Measured m;
            m.id = wanted.id;
            m.tier = wanted.tier;
            const glm::vec3 d = entities[k].move.position - eye;
            m.distance2 = d.x * d.x + d.y * d.y + d.z * d.z;
            while (at_waiting < waiting_.size() && waiting_[at_waiting].id < wanted.id) {
                ++at_waiting;
            }
            if (at_waiting < waiting_.size() && waiting_[at_waiting].id == wanted.id) {
                m.waited = waiting_[at_waiting].snapshots;
            }
            const std::uint32_t entries = encoder.counts().entries;
            const auto [masks_before, values_before] = column_bytes();
            if (encoder.carry(wanted.id, pose_at(k, wanted.tier), wanted.tier, snapshot)) {
                if (encoder.counts().entries != entries) {
                    const auto [masks_after, values_after] = column_bytes();
                    m.part = Part::entry;
                    m.mask_bytes = static_cast<std::uint32_t>(masks_after - masks_before);
                    m.bytes = static_cast<std::uint32_t>(values_after - values_before);
                } else {
                    m.part = encoder.last_added().held_ticks != 0 ? Part::held : Part::current;
                }
            } else if (!enter_allowed_.empty() && enter_allowed_[i] == 0) {
                m.part = Part::capped;
            } else {
                enter(wanted, k);
                m.part = Part::enter;
                m.bytes = static_cast<std::uint32_t>(
                    element_bytes(snapshot.enter(snapshot.enter_size() - 1).ByteSizeLong()));
            }
            parts.push_back(m);
            if (m.part == Part::capped) {
                ++last_deferred_;
            } else {
                known_.push_back(wanted.id);
            }
        });
        encoder.leave_the_rest(snapshot);
        // The body without enters and entries: the tick, the baseline tick, the leaves.
        std::size_t enters = 0;
        for (const Measured& m : parts) {
            enters += m.part == Part::enter ? m.bytes : 0;
        }
        const std::size_t columns_bytes =
            columns != nullptr ? columns->wire_bytes() : protocol::update_column_bytes(snapshot);
        return body_bytes(snapshot, columns) - enters - columns_bytes;
    };

    encoder.restart(snapshot, false);
    std::size_t fixed = measure();
    bool against_nothing = false;
    if (envelope_bytes(fixed) > protocol::kMaxSnapshotBytes) {
        // The leaves alone do not fit: against nothing there are none (the client forgets
        // what the snapshot does not hold), and the enters are capped.
        against_nothing = true;
        encoder.restart(snapshot, true);
        choose_enters(world, interest, eye, nullptr);
        fixed = measure();
    }
    measure_first_ = envelope_bytes(body_bytes(snapshot, columns)) > protocol::kMaxSnapshotBytes;
    if (!measure_first_ && !audit) {
        waiting_.clear(); // it fits as measured: nothing left out
        return;
    }

    std::vector<std::uint32_t>& order = scratch.order;
    order.clear();
    for (std::size_t j = 0; j < parts.size(); ++j) {
        parts[j].rank = kNoRank;
        if (parts[j].part == Part::entry || parts[j].part == Part::enter) {
            order.push_back(static_cast<std::uint32_t>(j));
        }
    }
    std::sort(order.begin(), order.end(), [&](std::uint32_t a_at, std::uint32_t b_at) {
        const Measured& a = parts[a_at];
        const Measured& b = parts[b_at];
        const bool a_promoted = a.waited >= kPromoteAfter;
        const bool b_promoted = b.waited >= kPromoteAfter;
        if (a_promoted != b_promoted) {
            return a_promoted;
        }
        if (a_promoted && a.waited != b.waited) {
            return a.waited > b.waited;
        }
        return a.tier != b.tier             ? a.tier < b.tier
               : a.distance2 != b.distance2 ? a.distance2 < b.distance2
                                            : a.id < b.id;
    });
    for (std::size_t r = 0; r < order.size(); ++r) {
        parts[order[r]].rank = static_cast<std::uint32_t>(r);
    }
    // The body with the first `count` of the order: each entry's head from the entry
    // before it that is written.
    const auto body_with = [&](std::size_t count) {
        std::size_t enters = 0;
        std::size_t heads = 0;
        std::size_t masks = 0;
        std::size_t values = 0;
        std::uint32_t last = 0;
        bool first = true;
        for (const Measured& m : parts) {
            if (m.rank >= count) {
                continue;
            }
            if (m.part == Part::enter) {
                enters += m.bytes;
                continue;
            }
            const std::uint32_t step = first ? m.id : m.id - last;
            // A head's mask bits never change its size: ids step by at least 1, and a
            // first entry's head below 16 is one byte whatever its mask.
            heads += CodedOutputStream::VarintSize64(
                std::uint64_t{step} << protocol::kHeadFieldBitCount | protocol::kHeadFields);
            masks += m.mask_bytes;
            values += m.bytes;
            last = m.id;
            first = false;
        }
        return fixed + enters + packed_bytes(heads) + packed_bytes(masks) + packed_bytes(values);
    };
    assert(body_with(order.size()) == body_bytes(snapshot, columns));
    // Room kept for audit poses when the client asked for them: at most an eighth of the
    // snapshot, so that a snapshot short of room still proves some of its poses.
    std::size_t audit_room = 0;
    if (audit) {
        for (const Measured& m : parts) {
            audit_room += m.tier == 0 && m.part != Part::capped ? kMaxAuditBytes : 0;
        }
        audit_room = std::min(audit_room, protocol::kMaxSnapshotBytes / 8);
    }
    const std::size_t room = protocol::kMaxSnapshotBytes - audit_room;
    std::size_t lo = 0; // within the limit (the leaves fit), if not within `room`
    std::size_t hi = order.size();
    if (envelope_bytes(body_with(hi)) <= protocol::kMaxSnapshotBytes) {
        lo = hi; // all fit: the audit poses get what room is left
    }
    while (lo < hi) {
        const std::size_t mid = lo + (hi - lo + 1) / 2;
        if (envelope_bytes(body_with(mid)) <= room) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    const std::size_t count = lo;

    encoder.restart(snapshot, against_nothing);
    known_.clear();
    last_deferred_ = 0;
    last_updates_deferred_ = 0;
    std::size_t body = body_with(count);
    bool auditing = audit;
    std::size_t at = 0;
    each_wanted([&](std::size_t i, std::size_t k) {
        const interest::Interest& wanted = interest[i];
        const Measured& m = parts[at++];
        assert(m.id == wanted.id);
        const bool written = m.rank < count;
        if (m.part == Part::capped || (m.part == Part::enter && !written)) {
            ++last_deferred_; // enters in a later snapshot
            return;
        }
        known_.push_back(wanted.id);
        if (m.part == Part::entry && !written) {
            ++last_updates_deferred_; // known, at its prediction until a later entry
            [[maybe_unused]] const bool carried = encoder.carry_unwritten(wanted.id, snapshot);
            assert(carried);
            return;
        }
        if (m.part == Part::enter) {
            enter(wanted, k);
        } else {
            [[maybe_unused]] const bool carried =
                encoder.carry(wanted.id, pose_at(k, wanted.tier), wanted.tier, snapshot);
            assert(carried);
        }
        if (auditing && wanted.tier == 0) {
            add_audit(entities[k], snapshot);
            const std::size_t bytes =
                element_bytes(snapshot.audit(snapshot.audit_size() - 1).ByteSizeLong());
            if (envelope_bytes(body + bytes) > protocol::kMaxSnapshotBytes) {
                snapshot.mutable_audit()->RemoveLast(); // no room for more audit poses
                auditing = false;
            } else {
                body += bytes;
            }
        }
    });
    assert(at == parts.size());
    encoder.leave_the_rest(snapshot);
    assert(body_bytes(snapshot, columns) == body);

    // Who waits for the next snapshot, and for how long already.
    std::vector<Waiting> next;
    next.reserve(waiting_.capacity());
    for (const Measured& m : parts) {
        const bool left_out = (m.part == Part::entry || m.part == Part::enter) && m.rank >= count;
        if (left_out) {
            const auto waited = static_cast<std::uint16_t>(
                std::min<int>(m.waited + 1, std::numeric_limits<std::uint16_t>::max()));
            next.push_back({m.id, waited});
        } else if (m.part == Part::held && m.waited > 0) {
            next.push_back({m.id, m.waited}); // not due this tick: still waiting
        }
    }
    waiting_.swap(next);
}

} // namespace dsoc::server
