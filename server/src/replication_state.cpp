#include "dsoc/server/replication_state.hpp"

namespace dsoc::server {

namespace {

void fill_state(const GameWorld& world, const Entity& e, protocol::pb::EntityState& s) {
    s.set_id(e.id);
    s.set_x(e.move.position.x);
    s.set_y(e.move.position.y);
    s.set_z(e.move.position.z);
    s.set_yaw(e.yaw_deg);
    s.set_pitch(e.pitch_deg);
    const glm::vec3 half = world.box_of(e).half_extents();
    s.set_half_x(half.x);
    s.set_half_y(half.y);
    s.set_half_z(half.z);
    s.set_kind(static_cast<std::uint32_t>(e.kind));
}

} // namespace

void ReplicationState::build_snapshot(const GameWorld& world,
                                      std::span<const std::uint32_t> interest, std::uint64_t tick,
                                      protocol::pb::Snapshot& snapshot) {
    snapshot.Clear();
    snapshot.set_server_tick(tick);
    next_known_.clear();

    // Merge two increasing id lists: old knowledge and the new interest set.
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < known_.size() || j < interest.size()) {
        const bool take_old =
            j == interest.size() || (i < known_.size() && known_[i] < interest[j]);
        const bool take_new =
            i == known_.size() || (j < interest.size() && interest[j] < known_[i]);
        if (take_old) { // known, no longer of interest (or gone from the world)
            snapshot.add_leave(known_[i]);
            sent_.erase(known_[i]);
            ++i;
            continue;
        }
        const std::uint32_t id = interest[j];
        const Entity* e = world.find(id);
        ++j;
        if (!take_new) {
            ++i; // known and still of interest
        }
        if (e == nullptr) { // contract breach: never leave a stale id known
            if (!take_new) {
                snapshot.add_leave(id);
                sent_.erase(id);
            }
            continue;
        }
        next_known_.push_back(id);
        if (take_new) {
            fill_state(world, *e, *snapshot.add_enter());
            sent_[id] = {e->move.position, e->yaw_deg, e->pitch_deg};
            continue;
        }
        SentState& last = sent_[id];
        if (last.position != e->move.position || last.yaw_deg != e->yaw_deg ||
            last.pitch_deg != e->pitch_deg) {
            protocol::pb::EntityUpdate& u = *snapshot.add_update();
            u.set_id(id);
            u.set_x(e->move.position.x);
            u.set_y(e->move.position.y);
            u.set_z(e->move.position.z);
            u.set_yaw(e->yaw_deg);
            u.set_pitch(e->pitch_deg);
            last = {e->move.position, e->yaw_deg, e->pitch_deg};
        }
    }
    known_.swap(next_known_);
}

} // namespace dsoc::server
