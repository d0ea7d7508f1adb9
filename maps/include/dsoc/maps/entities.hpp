#pragma once
// The Quake 3 entity string: { "key" "value" ... } blocks.

#include "dsoc/maps/load_error.hpp"
#include "dsoc/maps/map.hpp"

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace dsoc::maps {

/// One entity's key/value pairs in file order (keys may repeat; the last wins in lookups).
struct Entity {
    std::vector<std::pair<std::string, std::string>> pairs;
    /// The value of `key`, or empty when absent.
    [[nodiscard]] std::string_view value(std::string_view key) const;
};

/// Parses an entity string. Errors name the byte offset. `file` is used in errors.
[[nodiscard]] Result<std::vector<Entity>> parse_entities(std::string_view text,
                                                         const std::string& file);

/// Spawn points among the entities: info_player_deathmatch, info_player_start,
/// team_CTF_{red,blue}{spawn,player}. An origin that does not parse as three finite
/// numbers is an error (naming the entity).
[[nodiscard]] Result<std::vector<SpawnPoint>> spawn_points_from(const std::vector<Entity>& entities,
                                                                const std::string& file);

} // namespace dsoc::maps
