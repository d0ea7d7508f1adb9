#include "dsoc/eval/replication.hpp"

#include "dsoc/protocol/codec.hpp"

namespace dsoc::eval {

namespace {

constexpr std::uint32_t kKindBot = 0;
constexpr std::uint32_t kKindPlayer = 1;

} // namespace

SnapshotCost ClientReplication::send(const WorldFrame& frame,
                                     std::span<const std::uint32_t> interest, std::uint64_t tick,
                                     protocol::pb::Envelope& scratch,
                                     std::vector<std::uint8_t>& buffer) {
    if (sent_.size() < frame.entities.size()) {
        sent_.resize(frame.entities.size());
    }
    protocol::pb::Snapshot& snapshot = *scratch.mutable_snapshot();
    snapshot.Clear();
    snapshot.set_server_tick(tick);
    next_known_.clear();
    SnapshotCost cost;

    // Merge two increasing id lists: old knowledge and the new interest set.
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < known_.size() || j < interest.size()) {
        const bool take_old =
            j == interest.size() || (i < known_.size() && known_[i] < interest[j]);
        const bool take_new =
            i == known_.size() || (j < interest.size() && interest[j] < known_[i]);
        if (take_old) {
            snapshot.add_leave(known_[i]);
            ++cost.leaves;
            ++i;
            continue;
        }
        const std::uint32_t id = interest[j++];
        if (!take_new) {
            ++i;
        }
        const EntityFrame& e = frame.entities[id];
        next_known_.push_back(id);
        Sent& last = sent_[id];
        if (take_new) {
            auto& s = *snapshot.add_enter();
            s.set_id(id);
            s.set_x(e.position.x);
            s.set_y(e.position.y);
            s.set_z(e.position.z);
            s.set_yaw(e.yaw_deg);
            s.set_pitch(0.0f);
            const glm::vec3 half = e.box.half_extents();
            s.set_half_x(half.x);
            s.set_half_y(half.y);
            s.set_half_z(half.z);
            s.set_kind(id < players_ ? kKindPlayer : kKindBot);
            last = {e.position, e.yaw_deg};
            ++cost.enters;
            continue;
        }
        if (last.position != e.position || last.yaw_deg != e.yaw_deg) {
            auto& u = *snapshot.add_update();
            u.set_id(id);
            u.set_x(e.position.x);
            u.set_y(e.position.y);
            u.set_z(e.position.z);
            u.set_yaw(e.yaw_deg);
            u.set_pitch(0.0f);
            last = {e.position, e.yaw_deg};
            ++cost.updates;
        }
    }
    known_.swap(next_known_);
    buffer.clear();
    cost.bytes = static_cast<std::uint32_t>(protocol::encode_frame(scratch, buffer));
    return cost;
}

} // namespace dsoc::eval
