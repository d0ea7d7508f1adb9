#include "dsoc/server/replication_state.hpp"

#include "dsoc/protocol/interest_merge.hpp"

#include <algorithm>
#include <cassert>

namespace dsoc::server {

namespace {

/// How many entities ahead build_snapshot() asks for the encoder's remembered pose:
/// 500 clients' poses do not stay in cache from one tick to the next.
constexpr std::size_t kPrefetchAhead = 8;

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
            const std::uint64_t interval = protocol::update_interval(wanted.tier);
            if ((tick + wanted.id) % interval != 0) {
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
    last_acked_ = encoder.finish(snapshot);
    last_updates_ = last_acked_.enters + last_acked_.entries;
}

} // namespace dsoc::server
