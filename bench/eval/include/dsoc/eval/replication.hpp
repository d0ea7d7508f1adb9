#pragma once
// What one client is sent: the enter/update/leave Snapshot between what it knew and
// its new interest set, in the server's compact encoding (docs/protocol.md:
// quantized poses, updates as deltas against what the client last received, only
// changed fields present), written by the same dsoc::protocol::SnapshotEncoder the
// server uses and sized by the real protocol encoder. Every entity seen is sent on the
// near tier (updated every tick, finest quantum): the eval's policies give no
// level-of-detail hint, so all of them are measured with the same precision. An entity
// only heard goes on the heard tier, as the server sends it.
// dsoc-eval does not link the server (and Asio); it walks the server's rule
// (protocol::merge_interest, as dsoc::server::ReplicationState does) over the
// evaluation's frames.

#include "dsoc/eval/world_sim.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
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
    /// The update columns alone (protocol::update_column_bytes).
    std::uint32_t update_bytes = 0;
    /// Entities whose update carried a position change (the "moving" ones).
    std::uint32_t moving_updates = 0;
    /// Enters and updates of entities on the heard tier.
    std::uint32_t heard_entries = 0;
};

/// Size of an entity's uncompressed full state, the baseline of the compression
/// ratios: a 4-byte id and five 4-byte floats (x, y, z, yaw, pitch). [Units: bytes]
inline constexpr std::uint32_t kFullStateBytes = 24;

/// The pose an evaluation entity travels with (no pitch: the eval's entities only turn).
[[nodiscard]] protocol::Pose wire_pose(const EntityFrame& e);
/// The kind an entity is sent with: 1 (player) for an id below `players`, else 0 (bot).
[[nodiscard]] constexpr std::uint32_t wire_kind(std::uint32_t id, std::size_t players) {
    return id < players ? 1 : 0;
}

class ClientReplication {
public:
    /// Entities with an id below `players` are sent as kind 1 (player), others as 0 (bot).
    /// `quantization` must have passed protocol::validate(); tier 0 is used.
    explicit ClientReplication(std::size_t players = 0,
                               const protocol::QuantizationSettings& quantization = {})
        : encoder_(quantization), players_(players) {}

    /// Moves this client's knowledge to `interest` (increasing ids, entity ids of
    /// `frame`), those also in `heard` (increasing, a subset) on the heard tier, and
    /// returns what the snapshot of `tick` costs. `scratch` and `buffer` are reused
    /// between calls (one per thread).
    SnapshotCost send(const WorldFrame& frame, std::span<const std::uint32_t> interest,
                      std::span<const std::uint32_t> heard, std::uint64_t tick,
                      protocol::pb::Envelope& scratch, std::vector<std::uint8_t>& buffer);

    [[nodiscard]] const std::vector<std::uint32_t>& known() const { return known_; }

private:
    protocol::SnapshotEncoder encoder_;
    std::vector<std::uint32_t> known_; ///< increasing
    std::vector<std::uint32_t> next_known_;
    std::size_t players_;
};

} // namespace dsoc::eval
