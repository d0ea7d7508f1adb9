#pragma once
// One tick of an authoritative world as the world process publishes it and each
// interest gateway mirrors it (docs/scale-out.md has the byte layout): every entity's
// full state, so that a gateway's mirror (interest::GameWorld::mirror) reads exactly as
// the world did and its clients get the answers the single-process server gives.
// Floats travel bit for bit; no quantization.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/maps/load_error.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace dsoc::scaleout {

/// "DSWT": the first four bytes of a world tick.
inline constexpr std::uint32_t kWorldTickMagic = 0x54575344u;
inline constexpr std::uint16_t kWorldTickVersion = 2;
/// Entities a tick may carry at most (a decoder allocates no more). [Limit: entities]
inline constexpr std::uint32_t kMaxWorldTickEntities = 1u << 20;

struct WorldTick {
    /// world_key() of the publishing world: a gateway of another map or settings refuses it.
    std::uint64_t world_key = 0;
    /// The publishing world process's instance (WorldProcess::instance(): random, never
    /// 0, new at every start). Tick numbers are comparable within one instance only.
    std::uint64_t instance = 0;
    /// The world's step count when it was taken (1 after the first step). [Units: ticks]
    std::uint64_t tick = 0;
    std::uint64_t frags = 0;
    /// When the world encoded it: CLOCK_MONOTONIC (std::chrono::steady_clock on Linux)
    /// in nanoseconds. Comparable only on the same host: a gateway there measures the
    /// hop (tick published -> snapshots sent) with it. [Units: ns]
    std::uint64_t published_ns = 0;
    std::uint32_t next_id = 1;
    /// In increasing id order, ids in [1, next_id). Inputs (`Entity::input`) and bot
    /// brains do not travel: a mirror is read, not stepped.
    std::vector<interest::Entity> entities;
};

/// A 64-bit key of what a mirror must share with the world to read the same: the
/// map's occluders, PVS, collision brushes and spawn points, and the settings that
/// shape what is read (speed bound, teams, sounds, shots, respawn delay).
[[nodiscard]] std::uint64_t world_key(const maps::Map& map,
                                      const interest::WorldSettings& settings);

/// The instance a tick carries when no world process published it (benchmarks, tests).
inline constexpr std::uint64_t kNoProcessInstance = 1;

/// The bytes of `world`'s state at step `tick` of world process `instance` (never 0),
/// stamped `published_ns`.
void encode_world_tick(const interest::GameWorld& world, std::uint64_t world_key,
                       std::uint64_t tick, std::vector<std::byte>& out,
                       std::uint64_t published_ns = 0, std::uint64_t instance = kNoProcessInstance);
/// steady_clock now in nanoseconds: a WorldTick::published_ns.
[[nodiscard]] std::uint64_t monotonic_ns();

/// Parses `bytes` (from `source`, for messages): magic, version, instance (not 0),
/// sizes, every entity's fields (ids increasing and below next_id, known kinds and
/// flags, finite numbers, health and respawn countdowns in range), nothing left over.
/// With `expected_key`, a tick of another world is refused. Never throws on bad bytes.
[[nodiscard]] maps::Result<WorldTick>
decode_world_tick(std::span<const std::byte> bytes, const std::string& source,
                  std::optional<std::uint64_t> expected_key = std::nullopt);

/// Makes `mirror` read as `tick`'s world (interest::GameWorld::mirror); the tick must
/// come from decode_world_tick().
void apply_world_tick(WorldTick tick, interest::GameWorld& mirror);

} // namespace dsoc::scaleout
