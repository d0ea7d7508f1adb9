#include "dsoc/eval/replication.hpp"

#include "dsoc/protocol/codec.hpp"

namespace dsoc::eval {

namespace {

constexpr std::uint32_t kKindBot = 0;
constexpr std::uint32_t kKindPlayer = 1;

protocol::Pose pose_of(const EntityFrame& e) {
    return {e.position.x, e.position.y, e.position.z, e.yaw_deg, 0.0f};
}

} // namespace

SnapshotCost ClientReplication::send(const WorldFrame& frame,
                                     std::span<const std::uint32_t> interest, std::uint64_t tick,
                                     protocol::pb::Envelope& scratch,
                                     std::vector<std::uint8_t>& buffer) {
    protocol::pb::Snapshot& snapshot = *scratch.mutable_snapshot();
    encoder_.begin(tick, snapshot);
    next_known_.clear();
    SnapshotCost cost;
    constexpr std::uint32_t kPositionFields =
        protocol::kFieldX | protocol::kFieldY | protocol::kFieldZ | protocol::kFieldRebase;

    // Merge two increasing id lists: old knowledge and the new interest set.
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < known_.size() || j < interest.size()) {
        const bool take_old =
            j == interest.size() || (i < known_.size() && known_[i] < interest[j]);
        const bool take_new =
            i == known_.size() || (j < interest.size() && interest[j] < known_[i]);
        if (take_old) {
            encoder_.leave(known_[i], snapshot);
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
        if (take_new) {
            const glm::vec3 half = e.box.half_extents();
            encoder_.enter(id, pose_of(e), {half.x, half.y, half.z},
                           id < players_ ? kKindPlayer : kKindBot, 0, snapshot);
            ++cost.enters;
            continue;
        }
        if (encoder_.update(id, pose_of(e), 0, snapshot)) {
            ++cost.updates;
            const int entries = snapshot.update_fields_size();
            if ((snapshot.update_fields(entries - 1) & kPositionFields) != 0) {
                ++cost.moving_updates;
            }
        }
    }
    known_.swap(next_known_);
    cost.update_bytes = static_cast<std::uint32_t>(protocol::update_column_bytes(snapshot));
    buffer.clear();
    cost.bytes = static_cast<std::uint32_t>(protocol::encode_frame(scratch, buffer));
    return cost;
}

} // namespace dsoc::eval
