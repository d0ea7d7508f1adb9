// Fuzzes every reader of what travels between a world process and its gateways over
// NATS (dsoc/scaleout/world_tick.hpp, world_messages.hpp). The first byte picks the
// reader. A world tick the reader accepts must mirror into a world and encode back to
// the same bytes; an accepted message of the others must encode back to its bytes too.

#include "dsoc/maps/map.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/scaleout/world_messages.hpp"
#include "dsoc/scaleout/world_tick.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <span>
#include <vector>

namespace {

/// A world to mirror into: a generated map, no bots.
dsoc::interest::GameWorld& mirror() {
    static const std::shared_ptr<const dsoc::maps::Map> map = [] {
        auto loaded = dsoc::maps::load_map("gen:rooms:1", dsoc::maps::MapSearch{});
        if (!loaded) {
            std::abort();
        }
        return std::make_shared<const dsoc::maps::Map>(std::move(loaded).value());
    }();
    static dsoc::interest::GameWorld world(dsoc::interest::WorldSettings{.bots = 0}, map);
    return world;
}

} // namespace

namespace {

using dsoc::scaleout::IdBatchKind;

void same_or_abort(const std::vector<std::byte>& again, std::span<const std::byte> bytes) {
    if (again.size() != bytes.size() || !std::equal(again.begin(), again.end(), bytes.begin())) {
        std::abort(); // accepted bytes must be exactly what the encoder writes
    }
}

void world_tick(std::span<const std::byte> bytes) {
    auto tick = dsoc::scaleout::decode_world_tick(bytes, "fuzz");
    if (!tick.ok()) {
        (void)tick.error().message();
        return;
    }
    const std::uint64_t key = tick->world_key;
    const std::uint64_t number = tick->tick;
    const std::uint64_t published = tick->published_ns;
    const std::uint64_t instance = tick->instance;
    dsoc::scaleout::apply_world_tick(std::move(tick).value(), mirror());
    std::vector<std::byte> again;
    dsoc::scaleout::encode_world_tick(mirror(), key, number, again, published, instance);
    same_or_abort(again, bytes);
}

void other_message(std::uint8_t which, std::span<const std::byte> bytes) {
    std::vector<std::byte> again;
    switch (which % 5) {
    case 0:
        if (auto block = dsoc::scaleout::decode_id_block(bytes, "fuzz"); block.ok()) {
            dsoc::scaleout::encode_id_block(block.value(), again);
            same_or_abort(again, bytes);
        }
        break;
    case 1:
        if (auto request = dsoc::scaleout::decode_reserve_request(bytes, "fuzz"); request.ok()) {
            dsoc::scaleout::encode_reserve_request(request.value(), again);
            same_or_abort(again, bytes);
        }
        break;
    case 2:
        if (auto inputs = dsoc::scaleout::decode_inputs(bytes, "fuzz"); inputs.ok()) {
            dsoc::scaleout::encode_inputs({inputs->gateway, inputs->instance}, inputs->entries,
                                          again);
            same_or_abort(again, bytes);
        }
        break;
    default: {
        const IdBatchKind kind = which % 5 == 3 ? IdBatchKind::join : IdBatchKind::leave;
        if (auto ids = dsoc::scaleout::decode_id_batch(kind, bytes, "fuzz"); ids.ok()) {
            dsoc::scaleout::encode_id_batch(kind, {ids->gateway, ids->instance}, ids->entries,
                                            again);
            same_or_abort(again, bytes);
        }
    }
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) {
        return 0;
    }
    const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data) + 1, size - 1);
    if (data[0] < 128) {
        world_tick(bytes);
    } else {
        other_message(data[0], bytes);
    }
    return 0;
}
