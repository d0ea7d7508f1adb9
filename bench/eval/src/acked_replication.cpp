#include "dsoc/eval/acked_replication.hpp"

#include "dsoc/protocol/codec.hpp"

namespace dsoc::eval {

AckedClientReplication::AckedClientReplication(std::size_t players, const LinkModel& link,
                                               std::uint32_t client,
                                               const protocol::QuantizationSettings& quantization)
    : encoder_(quantization), decoder_(quantization), link_(link), rng_(link.seed * 7919u + client),
      players_(players) {}

void AckedClientReplication::deliver(std::uint64_t tick) {
    while (!to_client_.empty() && to_client_.front().arrives <= tick) {
        protocol::pb::Snapshot s;
        const bool parsed = s.ParseFromString(to_client_.front().bytes);
        to_client_.pop_front();
        const auto problems =
            parsed ? decoder_.apply(s) : std::vector<protocol::SnapshotProblem>{{"unparsable", ""}};
        if (!problems.empty()) {
            if (first_problem_.empty()) {
                first_problem_ = problems.front().kind + ": " + problems.front().detail;
            }
            continue;
        }
        const protocol::DeltaFrame* sent = encoder_.frame(s.server_tick());
        if (sent == nullptr || sent->entities != decoder_.newest()->entities) {
            ++mismatches_;
        }
    }
    // The client's next input carries its newest frame, as every input does.
    if (decoder_.newest_tick() && std::bernoulli_distribution(link_.loss)(rng_) == false) {
        acks_.emplace_back(tick + static_cast<std::uint64_t>(link_.one_way_ticks) + 1,
                           *decoder_.newest_tick());
    }
}

SnapshotCost AckedClientReplication::send(const WorldFrame& frame,
                                          std::span<const std::uint32_t> interest,
                                          std::span<const std::uint32_t> heard, std::uint64_t tick,
                                          protocol::pb::Envelope& scratch,
                                          std::vector<std::uint8_t>& buffer) {
    while (!acks_.empty() && acks_.front().first <= tick) {
        acked_ = acks_.front().second; // one delay for all: they arrive in order
        acks_.pop_front();
    }
    protocol::pb::Snapshot& snapshot = *scratch.mutable_snapshot();
    encoder_.begin(tick, acked_, snapshot);
    SnapshotCost cost;
    std::size_t next_heard = 0; // walks `heard` beside `interest` (both increasing)
    for (const std::uint32_t id : interest) {
        const EntityFrame& e = frame.entities[id];
        while (next_heard < heard.size() && heard[next_heard] < id) {
            ++next_heard;
        }
        const bool is_heard = next_heard < heard.size() && heard[next_heard] == id;
        const std::uint8_t tier = is_heard ? protocol::kHeardTier : 0;
        const glm::vec3 half = e.box.half_extents();
        encoder_.add(id, protocol::quantize(wire_pose(e), encoder_.settings(), tier), tier,
                     wire_kind(id, players_), {half.x, half.y, half.z}, snapshot);
    }
    const protocol::AckedSnapshotCounts counts = encoder_.finish(snapshot);
    full_ += counts.coded_against_baseline ? 0 : 1;
    cost.enters = counts.enters;
    cost.leaves = counts.leaves;
    cost.updates = counts.entries;
    cost.moving_updates = counts.moved;
    cost.update_bytes = static_cast<std::uint32_t>(protocol::update_column_bytes(snapshot));
    buffer.clear();
    cost.bytes = static_cast<std::uint32_t>(protocol::encode_frame(scratch, buffer));
    if (!std::bernoulli_distribution(link_.loss)(rng_)) {
        to_client_.push_back(
            {tick + static_cast<std::uint64_t>(link_.one_way_ticks), snapshot.SerializeAsString()});
    }
    deliver(tick);
    return cost;
}

} // namespace dsoc::eval
