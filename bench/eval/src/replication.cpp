#include "dsoc/eval/replication.hpp"

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/interest_merge.hpp"

namespace dsoc::eval {

protocol::Pose wire_pose(const EntityFrame& e) {
    return {e.position.x, e.position.y, e.position.z, e.yaw_deg, 0.0f};
}

SnapshotCost ClientReplication::send(const WorldFrame& frame,
                                     std::span<const std::uint32_t> interest,
                                     std::span<const std::uint32_t> heard, std::uint64_t tick,
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
    std::size_t next_heard = 0; // walks `heard` beside `interest` (both increasing)
    const auto send = [&](std::size_t j, bool was_known) {
        const std::uint32_t id = interest[j];
        const EntityFrame& e = frame.entities[id];
        next_known_.push_back(id);
        while (next_heard < heard.size() && heard[next_heard] < id) {
            ++next_heard;
        }
        const bool is_heard = next_heard < heard.size() && heard[next_heard] == id;
        const std::uint8_t tier = is_heard ? protocol::kHeardTier : 0;
        if (!was_known) {
            const glm::vec3 half = e.box.half_extents();
            encoder_.enter(id, wire_pose(e), {half.x, half.y, half.z}, wire_kind(id, players_),
                           tier, snapshot);
            ++cost.enters;
            cost.heard_entries += is_heard ? 1 : 0;
            return;
        }
        if (!protocol::due_at(id, tier, tick)) {
            return; // deferred, as the server does on a coarse tier
        }
        if (const std::uint32_t fields = encoder_.update(id, wire_pose(e), tier, snapshot);
            fields != 0) {
            ++cost.updates;
            cost.heard_entries += is_heard ? 1 : 0;
            cost.moving_updates += (fields & kPositionFields) != 0 ? 1 : 0;
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
