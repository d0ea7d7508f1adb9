// Fuzzes the client side of acknowledged-delta snapshots (AckedSnapshotDecoder): a
// stream of Snapshot messages, split by the input, applied to a decoder that already
// holds three frames (ticks 1 to 3) of a few entities, so that snapshots coded against
// them reach the prediction and the merge. Whatever the bytes, the decoder must report
// problems and never crash, overflow or read past a column; every frame it accepts
// must be well formed (ids increasing, tiers below kTiers, no angles on the heard tier,
// yaw steps in range, positions within the quantized range), and a snapshot it rejects
// must leave the newest frame as it was.

#include "dsoc/protocol/acked_snapshot.hpp"
#include "snapshot_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

namespace {

void check(const dsoc::protocol::DeltaFrame& frame, std::uint32_t steps) {
    using namespace dsoc::protocol;
    for (std::size_t i = 0; i < frame.entities.size(); ++i) {
        const FrameEntity& e = frame.entities[i];
        const bool in_range =
            std::abs(static_cast<std::int64_t>(e.pose.x)) <= kMaxQuantizedCoordinate &&
            std::abs(static_cast<std::int64_t>(e.pose.y)) <= kMaxQuantizedCoordinate &&
            std::abs(static_cast<std::int64_t>(e.pose.z)) <= kMaxQuantizedCoordinate;
        if ((i > 0 && frame.entities[i - 1].id >= e.id) || e.tier >= kTiers ||
            (e.tier == kHeardTier && (e.pose.yaw != 0 || e.pose.pitch != 0)) || e.pose.yaw < 0 ||
            static_cast<std::uint32_t>(e.pose.yaw) >= steps || !in_range ||
            e.held_ticks >= update_interval(e.tier) || e.motion_ticks > kMaxPredictedTicks) {
            std::abort();
        }
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace dsoc::protocol;
    if (size < 1) {
        return 0;
    }
    const QuantizationSettings settings = dsoc::fuzzing::settings_from(data[0]);
    AckedSnapshotDecoder decoder(settings);
    {
        AckedSnapshotEncoder encoder(settings); // three plausible frames
        pb::Snapshot s;
        for (std::uint64_t tick = 1; tick <= 3; ++tick) {
            // Ticks 2 and 3 both against tick 1: the decoder then keeps all three (it
            // forgets only the frames older than the newest snapshot's baseline).
            encoder.begin(tick, tick == 1 ? std::nullopt : std::optional<std::uint64_t>(1), s);
            for (std::uint32_t id = 1; id <= 4; ++id) {
                const auto tier = static_cast<std::uint8_t>(id % kTiers);
                const Pose pose{100.0f * static_cast<float>(id * tick), -50.0f, 24.0f,
                                30.0f * static_cast<float>(tick), 0.0f};
                encoder.add(id, quantize(pose, settings, tier), tier, 0, {15.0f, 15.0f, 28.0f}, s);
            }
            encoder.finish(s);
            if (!decoder.apply(s).empty()) {
                std::abort();
            }
        }
    }
    // The rest: [length byte][that many bytes of a serialized Snapshot] ...
    pb::Snapshot snapshot;
    dsoc::fuzzing::for_each_length_prefixed(
        data, size, 1, [&](const std::uint8_t* bytes, std::size_t n) {
            if (!snapshot.ParseFromArray(bytes, static_cast<int>(n)) ||
                !decoder.apply(snapshot).empty()) {
                return;
            }
            check(*decoder.newest(), settings.angle_steps);
            for (const FrameEntity& e : decoder.newest()->entities) {
                const auto pose = decoder.pose(e.id);
                if (!pose || !std::isfinite(pose->x) || !std::isfinite(pose->yaw_deg)) {
                    std::abort();
                }
            }
        });
    return 0;
}
