#include "dsoc/eval/replication.hpp"

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/interest_merge.hpp"

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

    // The server's rule (protocol::merge_interest): old knowledge against the new set.
    const auto leave = [&](std::uint32_t id) {
        encoder_.leave(id, snapshot);
        ++cost.leaves;
    };
    const auto send = [&](std::size_t j, bool was_known) {
        const std::uint32_t id = interest[j];
        const EntityFrame& e = frame.entities[id];
        next_known_.push_back(id);
        if (!was_known) {
            const glm::vec3 half = e.box.half_extents();
            encoder_.enter(id, pose_of(e), {half.x, half.y, half.z},
                           id < players_ ? kKindPlayer : kKindBot, 0, snapshot);
            ++cost.enters;
            return;
        }
        if (encoder_.update(id, pose_of(e), 0, snapshot)) {
            ++cost.updates;
            const int entries = snapshot.update_fields_size();
            if ((snapshot.update_fields(entries - 1) & kPositionFields) != 0) {
                ++cost.moving_updates;
            }
        }
    };
    protocol::merge_interest(
        known_, interest, [](std::uint32_t id) { return id; }, leave, send);
    known_.swap(next_known_);
    cost.update_bytes = static_cast<std::uint32_t>(protocol::update_column_bytes(snapshot));
    buffer.clear();
    cost.bytes = static_cast<std::uint32_t>(protocol::encode_frame(scratch, buffer));
    return cost;
}

} // namespace dsoc::eval
