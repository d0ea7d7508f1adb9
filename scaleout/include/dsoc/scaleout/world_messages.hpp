#pragma once
// What gateways and the world process send each other besides ticks (docs/scale-out.md
// has the layouts): blocks of reserved entity ids, batches of the clients' inputs, and
// joins and leaves. Little-endian, fixed sizes; every decoder checks the magic, the
// version, the length and every value, and never throws on bad bytes. What a gateway
// sends names the world instance it follows (IdBlock::instance, WorldTick::instance),
// so that another world process on the same name takes none of it.

#include "dsoc/maps/load_error.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dsoc::scaleout {

/// 3: gateway messages name the world instance they are for (2 did not).
inline constexpr std::uint16_t kWorldMessageVersion = 3;
/// Inputs or leaves one message may carry at most. [Limit: entries]
inline constexpr std::uint32_t kMaxBatchEntries = 1u << 16;

/// A random id, never 0: a gateway's in its messages, a world process's instance.
[[nodiscard]] std::uint64_t random_id();

/// Entity ids a gateway may give its new players: [first_id, first_id + count), reserved
/// by the world for it (a "reserve" request's answer), so a hello is answered at once.
struct IdBlock {
    std::uint64_t world_key = 0;
    /// The world process that reserved them (WorldProcess::instance(), never 0): another
    /// instance of the world, a restarted one, knows nothing of them.
    std::uint64_t instance = 0;
    std::uint32_t first_id = 0;
    std::uint32_t count = 0;
};
/// Ids one reserve request may ask for at most. [Limit: ids]
inline constexpr std::uint32_t kMaxIdBlock = 4096;

/// A gateway's request for a block of ids, reserved for that gateway alone.
struct ReserveRequest {
    std::uint64_t gateway = 0; ///< the asking gateway's id (as in its batches; never 0)
    /// The world instance the gateway follows (never 0: a gateway asks once it follows
    /// one, so that two world processes on one name never both answer). A world of
    /// another instance ignores the request.
    std::uint64_t instance = 0;
    std::uint32_t count = 0; ///< 1..kMaxIdBlock
};

/// One client's intent for the next world step (interest::GameWorld::set_player_input
/// and fire).
struct PlayerInput {
    std::uint32_t entity_id = 0;
    glm::vec3 wish{0.0f}; ///< horizontal; z ignored; finite, length <= 1 after clamping
    bool jump = false;
    bool fire = false;
    float yaw_deg = 0.0f;   ///< finite
    float pitch_deg = 0.0f; ///< finite
};

void encode_id_block(const IdBlock& block, std::vector<std::byte>& out);
[[nodiscard]] maps::Result<IdBlock> decode_id_block(std::span<const std::byte> bytes,
                                                    const std::string& source);
void encode_reserve_request(const ReserveRequest& request, std::vector<std::byte>& out);
[[nodiscard]] maps::Result<ReserveRequest> decode_reserve_request(std::span<const std::byte> bytes,
                                                                  const std::string& source);

/// Who sends a batch, and to which world: the gateway's random id (for the world's
/// bookkeeping) and the world instance whose ticks it serves (a world of another
/// instance drops the batch). Neither is ever 0.
struct BatchFrom {
    std::uint64_t gateway = 0;
    std::uint64_t instance = 0;
};

/// A batch of entries from one gateway.
template <typename Entry>
struct Batch {
    std::uint64_t gateway = 0;
    std::uint64_t instance = 0;
    std::vector<Entry> entries;
};

/// Sent every tick by every gateway, empty or not: it is also the gateway's heartbeat
/// (a world forgets the players of a gateway it has not heard from for a while).
void encode_inputs(BatchFrom from, std::span<const PlayerInput> inputs,
                   std::vector<std::byte>& out);
/// Refuses the whole batch on any bad entry (non-finite numbers, |wish| components
/// over 1, unknown flags, entity id 0, gateway or instance 0).
[[nodiscard]] maps::Result<Batch<PlayerInput>> decode_inputs(std::span<const std::byte> bytes,
                                                             const std::string& source);

/// What a message on a world's `gateway` subject is, by its magic: joins, inputs and
/// leaves share one subject so that the world takes them in the order a gateway sent
/// them (a leave never before its join). Nothing for another magic.
enum class GatewayMessage : std::uint8_t { join, input, leave };
[[nodiscard]] std::optional<GatewayMessage> gateway_message_of(std::span<const std::byte> bytes);

/// Joins (players to spawn, ids from the gateway's blocks) and leaves: lists of entity
/// ids, each kind with its own magic so that one is never read as the other.
enum class IdBatchKind : std::uint8_t { join, leave };
void encode_id_batch(IdBatchKind kind, BatchFrom from, std::span<const std::uint32_t> entity_ids,
                     std::vector<std::byte>& out);
[[nodiscard]] maps::Result<Batch<std::uint32_t>>
decode_id_batch(IdBatchKind kind, std::span<const std::byte> bytes, const std::string& source);

} // namespace dsoc::scaleout
