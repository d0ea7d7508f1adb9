#include "dsoc/scaleout/world_messages.hpp"

#include "little_endian.hpp"

#include <cmath>
#include <cstdint>
#include <random>

namespace dsoc::scaleout {

namespace {

constexpr std::uint32_t kBlockMagic = 0x42575344u;   // "DSWB"
constexpr std::uint32_t kReserveMagic = 0x52575344u; // "DSWR"
constexpr std::uint32_t kJoinMagic = 0x4a575344u;    // "DSWJ"
constexpr std::uint32_t kInputMagic = 0x49575344u;   // "DSWI"
constexpr std::uint32_t kLeaveMagic = 0x4c575344u;   // "DSWL"
constexpr std::size_t kBlockBytes = 32;
constexpr std::size_t kReserveBytes = 28;
constexpr std::size_t kBatchHeaderBytes = 28;
constexpr std::size_t kInputBytes = 24;
constexpr std::uint8_t kJump = 1;
constexpr std::uint8_t kFire = 2;

void put_header(std::vector<std::byte>& out, std::uint32_t magic) {
    put(out, magic);
    put(out, kWorldMessageVersion);
    put(out, std::uint16_t{0});
}

/// Why the first 8 bytes are not a header of `magic` (or ""), `name` naming the kind.
std::string header_problem(std::span<const std::byte> bytes, std::uint32_t magic,
                           const char* name) {
    if (bytes.size() < 8) {
        return std::to_string(bytes.size()) + " bytes: too short for a " + name;
    }
    if (get<std::uint32_t>(bytes, 0) != magic) {
        return std::string("not a ") + name + " (wrong magic)";
    }
    if (const auto version = get<std::uint16_t>(bytes, 4); version != kWorldMessageVersion) {
        return "version " + std::to_string(version) + ", this build reads " +
               std::to_string(kWorldMessageVersion);
    }
    if (get<std::uint16_t>(bytes, 6) != 0) {
        return "reserved field not 0";
    }
    return {};
}

void put_batch_header(std::vector<std::byte>& out, std::uint32_t magic, BatchFrom from,
                      std::size_t count) {
    out.clear();
    put_header(out, magic);
    put(out, from.gateway);
    put(out, from.instance);
    put(out, static_cast<std::uint32_t>(count));
}

/// The gateway, instance and entry count of a batch whose entries take `entry_bytes`
/// each, after checking that exactly that many follow; `problem` says why not.
template <typename Entry>
std::uint32_t batch_count(std::span<const std::byte> bytes, std::size_t entry_bytes,
                          Batch<Entry>& batch, std::string& problem) {
    if (bytes.size() < kBatchHeaderBytes) {
        problem = std::to_string(bytes.size()) + " bytes: no gateway, instance and entry count";
        return 0;
    }
    batch.gateway = get<std::uint64_t>(bytes, 8);
    batch.instance = get<std::uint64_t>(bytes, 16);
    const auto count = get<std::uint32_t>(bytes, 24);
    if (batch.gateway == 0) {
        problem = "gateway id 0";
    } else if (batch.instance == 0) {
        problem = "world instance 0";
    } else if (count > kMaxBatchEntries ||
               bytes.size() != kBatchHeaderBytes + static_cast<std::size_t>(count) * entry_bytes) {
        problem = std::to_string(count) + " entries in " + std::to_string(bytes.size()) +
                  " bytes (each takes " + std::to_string(entry_bytes) + ", at most " +
                  std::to_string(kMaxBatchEntries) + ")";
    }
    return count;
}

} // namespace

std::uint64_t random_id() {
    std::random_device device;
    std::uint64_t id = 0;
    while (id == 0) {
        id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
    }
    return id;
}

std::optional<GatewayMessage> gateway_message_of(std::span<const std::byte> bytes) {
    if (bytes.size() < sizeof(std::uint32_t)) {
        return std::nullopt;
    }
    switch (get<std::uint32_t>(bytes, 0)) {
    case kJoinMagic:
        return GatewayMessage::join;
    case kInputMagic:
        return GatewayMessage::input;
    case kLeaveMagic:
        return GatewayMessage::leave;
    default:
        return std::nullopt;
    }
}

void encode_id_block(const IdBlock& block, std::vector<std::byte>& out) {
    out.clear();
    put_header(out, kBlockMagic);
    put(out, block.world_key);
    put(out, block.instance);
    put(out, block.first_id);
    put(out, block.count);
}

maps::Result<IdBlock> decode_id_block(std::span<const std::byte> bytes, const std::string& source) {
    if (std::string problem = header_problem(bytes, kBlockMagic, "id block"); !problem.empty()) {
        return maps::LoadError{source, "id block", problem};
    }
    if (bytes.size() != kBlockBytes) {
        return maps::LoadError{source, "id block",
                               std::to_string(bytes.size()) + " bytes, an id block has " +
                                   std::to_string(kBlockBytes)};
    }
    IdBlock block{get<std::uint64_t>(bytes, 8), get<std::uint64_t>(bytes, 16),
                  get<std::uint32_t>(bytes, 24), get<std::uint32_t>(bytes, 28)};
    if (block.instance == 0) {
        return maps::LoadError{source, "id block", "world instance 0"};
    }
    if (block.first_id == 0 || block.count == 0 || block.count > kMaxIdBlock ||
        block.first_id > UINT32_MAX - block.count) {
        return maps::LoadError{source, "id block",
                               "ids " + std::to_string(block.first_id) + " + " +
                                   std::to_string(block.count) +
                                   " (the first is at least 1, 1..4096 of them, no wrap)"};
    }
    return block;
}

void encode_reserve_request(const ReserveRequest& request, std::vector<std::byte>& out) {
    out.clear();
    put_header(out, kReserveMagic);
    put(out, request.gateway);
    put(out, request.instance);
    put(out, request.count);
}

maps::Result<ReserveRequest> decode_reserve_request(std::span<const std::byte> bytes,
                                                    const std::string& source) {
    if (std::string problem = header_problem(bytes, kReserveMagic, "reserve request");
        !problem.empty()) {
        return maps::LoadError{source, "reserve request", problem};
    }
    if (bytes.size() != kReserveBytes) {
        return maps::LoadError{source, "reserve request",
                               std::to_string(bytes.size()) + " bytes, a reserve request has " +
                                   std::to_string(kReserveBytes)};
    }
    const ReserveRequest request{get<std::uint64_t>(bytes, 8), get<std::uint64_t>(bytes, 16),
                                 get<std::uint32_t>(bytes, 24)};
    if (request.gateway == 0) {
        return maps::LoadError{source, "reserve request", "gateway id 0"};
    }
    if (request.instance == 0) {
        return maps::LoadError{source, "reserve request",
                               "world instance 0 (a gateway asks the instance it follows)"};
    }
    if (request.count == 0 || request.count > kMaxIdBlock) {
        return maps::LoadError{source, "reserve request",
                               std::to_string(request.count) + " ids asked for (1..4096)"};
    }
    return request;
}

void encode_inputs(BatchFrom from, std::span<const PlayerInput> inputs,
                   std::vector<std::byte>& out) {
    put_batch_header(out, kInputMagic, from, inputs.size());
    for (const PlayerInput& in : inputs) {
        put(out, in.entity_id);
        put(out, in.wish.x);
        put(out, in.wish.y);
        put(out, in.yaw_deg);
        put(out, in.pitch_deg);
        put(out, static_cast<std::uint8_t>((in.jump ? kJump : 0) | (in.fire ? kFire : 0)));
        put(out, std::uint8_t{0});
        put(out, std::uint16_t{0});
    }
}

maps::Result<Batch<PlayerInput>> decode_inputs(std::span<const std::byte> bytes,
                                               const std::string& source) {
    if (std::string problem = header_problem(bytes, kInputMagic, "input batch"); !problem.empty()) {
        return maps::LoadError{source, "input batch", problem};
    }
    std::string problem;
    Batch<PlayerInput> batch;
    const std::uint32_t count = batch_count(bytes, kInputBytes, batch, problem);
    if (!problem.empty()) {
        return maps::LoadError{source, "input batch", problem};
    }
    std::vector<PlayerInput>& inputs = batch.entries;
    inputs.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::size_t at = kBatchHeaderBytes + i * kInputBytes;
        PlayerInput& in = inputs[i];
        in.entity_id = get<std::uint32_t>(bytes, at);
        in.wish = {get<float>(bytes, at + 4), get<float>(bytes, at + 8), 0.0f};
        in.yaw_deg = get<float>(bytes, at + 12);
        in.pitch_deg = get<float>(bytes, at + 16);
        const auto flags = get<std::uint8_t>(bytes, at + 20);
        in.jump = (flags & kJump) != 0;
        in.fire = (flags & kFire) != 0;
        const std::string part = "input " + std::to_string(i);
        if (in.entity_id == 0) {
            return maps::LoadError{source, part, "entity id 0"};
        }
        if ((flags & ~(kJump | kFire)) != 0 || get<std::uint8_t>(bytes, at + 21) != 0 ||
            get<std::uint16_t>(bytes, at + 22) != 0) {
            return maps::LoadError{source, part, "unknown flags or padding not 0"};
        }
        if (!(std::fabs(in.wish.x) <= 1.0f && std::fabs(in.wish.y) <= 1.0f) ||
            !std::isfinite(in.yaw_deg) || !std::isfinite(in.pitch_deg)) {
            return maps::LoadError{source, part, "wish outside -1..1 or view angles not finite"};
        }
    }
    return batch;
}

void encode_id_batch(IdBatchKind kind, BatchFrom from, std::span<const std::uint32_t> entity_ids,
                     std::vector<std::byte>& out) {
    put_batch_header(out, kind == IdBatchKind::join ? kJoinMagic : kLeaveMagic, from,
                     entity_ids.size());
    for (const std::uint32_t id : entity_ids) {
        put(out, id);
    }
}

maps::Result<Batch<std::uint32_t>>
decode_id_batch(IdBatchKind kind, std::span<const std::byte> bytes, const std::string& source) {
    const char* name = kind == IdBatchKind::join ? "join batch" : "leave batch";
    if (std::string problem =
            header_problem(bytes, kind == IdBatchKind::join ? kJoinMagic : kLeaveMagic, name);
        !problem.empty()) {
        return maps::LoadError{source, name, problem};
    }
    std::string problem;
    Batch<std::uint32_t> batch;
    const std::uint32_t count = batch_count(bytes, sizeof(std::uint32_t), batch, problem);
    if (!problem.empty()) {
        return maps::LoadError{source, name, problem};
    }
    std::vector<std::uint32_t>& ids = batch.entries;
    ids.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
        ids[i] = get<std::uint32_t>(bytes, kBatchHeaderBytes + i * sizeof(std::uint32_t));
        if (ids[i] == 0) {
            return maps::LoadError{source, std::string(name) + " entry " + std::to_string(i),
                                   "entity id 0"};
        }
    }
    return batch;
}

} // namespace dsoc::scaleout
