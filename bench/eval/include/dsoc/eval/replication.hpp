#pragma once
// What one client is sent: the enter/update/leave Snapshot between what it knew and
// its new interest set, encoded with the real protocol encoder to count bytes.
// The same rules as dsoc::server::ReplicationState (server/src/replication_state.cpp),
// re-stated here over the evaluation's frames so that dsoc-eval does not link the
// server (and Asio): enter with full state, update for a known entity whose
// position or facing changed since it was last sent, leave for ids no longer in the set.

#include "dsoc/eval/world_sim.hpp"
#include "dsoc/protocol/messages.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::eval {

struct SnapshotCost {
    std::uint32_t enters = 0;
    std::uint32_t updates = 0;
    std::uint32_t leaves = 0;
    std::uint32_t bytes = 0; ///< the encoded frame, 4-byte length header included
};

class ClientReplication {
public:
    /// Entities with an id below `players` are sent as kind 1 (player), others as 0 (bot).
    explicit ClientReplication(std::size_t players = 0) : players_(players) {}

    /// Moves this client's knowledge to `interest` (increasing ids, entity ids of
    /// `frame`) and returns what the snapshot of `tick` costs. `scratch` and `buffer`
    /// are reused between calls (one per thread).
    SnapshotCost send(const WorldFrame& frame, std::span<const std::uint32_t> interest,
                      std::uint64_t tick, protocol::pb::Envelope& scratch,
                      std::vector<std::uint8_t>& buffer);

    [[nodiscard]] const std::vector<std::uint32_t>& known() const { return known_; }

private:
    struct Sent {
        glm::vec3 position{0.0f};
        float yaw_deg = 0.0f;
    };
    std::vector<std::uint32_t> known_; ///< increasing
    std::vector<std::uint32_t> next_known_;
    std::vector<Sent> sent_; ///< indexed by entity id
    std::size_t players_;
};

} // namespace dsoc::eval
