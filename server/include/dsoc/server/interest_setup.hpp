#pragma once
// The server's interest layer: the world and the interest policy of dsoc::interest,
// made from the server's settings. ServerConfig becomes interest::WorldSettings and
// interest::PolicySettings here and nowhere else; the baked table comes from the
// cache (or is baked, with progress on stderr) and is logged.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/server/server_config.hpp"
#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <memory>

namespace dsoc::server {

/// The world `config` describes (bots, max_speed, seed).
[[nodiscard]] interest::WorldSettings world_settings(const ServerConfig& config);

/// The policy settings `config` describes; the DSOCConfig is dsoc_config(config) (flat
/// keys, the occlusion policy's presets, then the [dsoc] table).
[[nodiscard]] interest::PolicySettings policy_settings(const ServerConfig& config);

/// The map's baked cell visibility table for config.baked_stage: from the cache, or
/// baked (progress on stderr) and saved. Throws std::runtime_error when it cannot be had,
/// or when a stop was asked for during the bake (startup_stop.hpp; the partial bake is
/// saved and the next start goes on from it).
[[nodiscard]] std::shared_ptr<const visibility::CellVisibilityTable>
baked_table(const ServerConfig& config, const interest::GameWorld& world,
            const visibility::OccluderScene& scene);

/// interest::make_policy() with policy_settings(config) and baked_table(); config must
/// have passed validate().
[[nodiscard]] std::unique_ptr<interest::InterestPolicy>
make_policy(const ServerConfig& config, const interest::GameWorld& world);

} // namespace dsoc::server
