#include "dsoc/server/replication_state.hpp"

namespace dsoc::server {

namespace {

void add_audit(const Entity& e, protocol::pb::Snapshot& snapshot) {
    protocol::pb::AuditPose& a = *snapshot.add_audit();
    a.set_id(e.id);
    a.set_x(e.move.position.x);
    a.set_y(e.move.position.y);
    a.set_z(e.move.position.z);
    a.set_yaw(e.yaw_deg);
    a.set_pitch(e.pitch_deg);
}

} // namespace

protocol::Pose pose_of(const Entity& e) {
    return {e.move.position.x, e.move.position.y, e.move.position.z, e.yaw_deg, e.pitch_deg};
}

void ReplicationState::build_snapshot(const GameWorld& world, std::span<const Interest> interest,
                                      std::uint64_t tick, bool audit,
                                      protocol::pb::Snapshot& snapshot) {
    encoder_.begin(tick, snapshot);
    next_known_.clear();

    // Merge two increasing id lists: old knowledge and the new interest set.
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < known_.size() || j < interest.size()) {
        const bool take_old =
            j == interest.size() || (i < known_.size() && known_[i] < interest[j].id);
        const bool take_new =
            i == known_.size() || (j < interest.size() && interest[j].id < known_[i]);
        if (take_old) { // known, no longer of interest (or gone from the world)
            encoder_.leave(known_[i], snapshot);
            ++i;
            continue;
        }
        const Interest wanted = interest[j];
        const Entity* e = world.find(wanted.id);
        ++j;
        if (!take_new) {
            ++i; // known and still of interest
        }
        if (e == nullptr) { // contract breach: never leave a stale id known
            if (!take_new) {
                encoder_.leave(wanted.id, snapshot);
            }
            continue;
        }
        next_known_.push_back(wanted.id);
        if (take_new) {
            const glm::vec3 half = world.box_of(*e).half_extents();
            encoder_.enter(wanted.id, pose_of(*e), {half.x, half.y, half.z},
                           static_cast<std::uint32_t>(e->kind), wanted.tier, snapshot);
        } else {
            const std::uint64_t interval = std::uint64_t{1} << wanted.tier;
            if ((tick + wanted.id) % interval != 0) {
                continue; // deferred: this coarse-tier entity is not due this tick
            }
            encoder_.update(wanted.id, pose_of(*e), wanted.tier, snapshot);
        }
        if (audit) {
            add_audit(*e, snapshot);
        }
    }
    known_.swap(next_known_);
}

} // namespace dsoc::server
