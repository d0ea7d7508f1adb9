// Fuzzes the client side of compact snapshots (SnapshotDecoder): a stream of
// Snapshot messages, split by the input, applied to one replica that starts with a
// few known entities. Whatever the bytes, the decoder must report problems and never
// crash, overflow or read past a column; afterwards every known entity's pose must be
// finite.

#include "dsoc/protocol/compact_snapshot.hpp"
#include "snapshot_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace dsoc::protocol;
    if (size < 1) {
        return 0;
    }
    const QuantizationSettings settings = dsoc::fuzzing::settings_from(data[0]);
    SnapshotDecoder decoder(settings);
    {
        SnapshotEncoder encoder(settings); // a plausible starting replica
        pb::Snapshot start;
        encoder.begin(1, start);
        for (std::uint32_t id = 1; id <= 4; ++id) {
            encoder.enter(id, {100.0f * static_cast<float>(id), -50.0f, 24.0f, 90.0f, 0.0f},
                          {15.0f, 15.0f, 28.0f}, 0, static_cast<std::uint8_t>(id % 3), start);
        }
        if (!decoder.apply(start).empty()) {
            std::abort();
        }
    }
    // The rest: [length byte][that many bytes of a serialized Snapshot] ...
    pb::Snapshot snapshot;
    dsoc::fuzzing::for_each_length_prefixed(
        data, size, 1, [&](const std::uint8_t* bytes, std::size_t n) {
            if (snapshot.ParseFromArray(bytes, static_cast<int>(n))) {
                (void)decoder.apply(snapshot);
                double worst = 0.0;
                (void)decoder.check_audit(snapshot, worst);
            }
        });
    decoder.entities().for_each([&](std::uint32_t id, const ReplicaEntity& /*entity*/) {
        const auto pose = decoder.pose(id);
        if (!pose || !std::isfinite(pose->x) || !std::isfinite(pose->yaw_deg)) {
            std::abort();
        }
    });
    return 0;
}
