#pragma once
// What one client is sent over an unreliable link: acknowledged-delta snapshots
// (dsoc::protocol::AckedSnapshotEncoder, docs/protocol.md "Acknowledged deltas") from the
// same interest sets and tiers as ClientReplication, carried by a simulated link that
// delays and loses them, decoded by the client's AckedSnapshotDecoder, whose newest
// frame goes back as the acknowledgement its next input carries. Every snapshot the
// client applies is compared with the server's frame of that tick (mismatches(): must
// stay 0), so a measurement of bytes is also a check of the codec.

#include "dsoc/eval/replication.hpp"
#include "dsoc/eval/world_sim.hpp"
#include "dsoc/protocol/acked_snapshot.hpp"

#include <cstdint>
#include <deque>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace dsoc::eval {

/// A link between server and client, the same both ways.
struct LinkModel {
    /// How long a datagram takes, one way. [Units: ticks] [Limit: 0..kAckedHistory/2]
    /// 0: a loopback or LAN link; the snapshot of tick t is acknowledged by the input the
    /// server reads before tick t + 1.
    int one_way_ticks = 0;
    /// The share of datagrams lost, each independently. [Limit: 0..1]
    double loss = 0.0;
    std::uint32_t seed = 1; ///< of the losses
};

class AckedClientReplication {
public:
    AckedClientReplication(std::size_t players, const LinkModel& link, std::uint32_t client,
                           const protocol::QuantizationSettings& quantization = {});

    /// Sends the snapshot of `tick` that moves the client to `interest` (increasing ids of
    /// `frame`), those also in `heard` on the heard tier, coded against the newest frame
    /// the server has an acknowledgement for; delivers what the link has due by `tick`.
    /// Returns what the snapshot costs: `updates` are its update entries, `moving_updates`
    /// the entities it carries to a new position (with an entry or predicted exactly).
    SnapshotCost send(const WorldFrame& frame, std::span<const std::uint32_t> interest,
                      std::span<const std::uint32_t> heard, std::uint64_t tick,
                      protocol::pb::Envelope& scratch, std::vector<std::uint8_t>& buffer);

    /// Snapshots the client applied whose frame was not the server's (a codec bug).
    [[nodiscard]] std::uint64_t mismatches() const { return mismatches_; }
    /// Snapshots coded against nothing (the first, and after a loss longer than the history).
    [[nodiscard]] std::uint64_t full_snapshots() const { return full_; }
    /// The first problem the decoder reported for a snapshot it had to apply, if any.
    [[nodiscard]] const std::string& first_problem() const { return first_problem_; }

private:
    struct InFlight {
        std::uint64_t arrives = 0; ///< tick
        std::string bytes;         ///< the serialized snapshot
    };
    void deliver(std::uint64_t tick);

    protocol::AckedSnapshotEncoder encoder_;
    protocol::AckedSnapshotDecoder decoder_;
    LinkModel link_;
    std::mt19937 rng_;
    std::size_t players_;
    std::deque<InFlight> to_client_;
    std::deque<std::pair<std::uint64_t, std::uint64_t>> acks_; ///< arrival tick, acked tick
    std::optional<std::uint64_t> acked_;
    std::uint64_t mismatches_ = 0;
    std::uint64_t full_ = 0;
    std::string first_problem_;
};

} // namespace dsoc::eval
