#pragma once
// Maps for tests: small generated worlds that need no files, loaded once per process.

#include "dsoc/maps/map_source.hpp"

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>

namespace dsoc::testing {

/// A generated rooms-and-corridors map ("gen:rooms:1"). Throws if it cannot be made.
inline std::shared_ptr<const maps::Map> rooms_map() {
    static const std::shared_ptr<const maps::Map> map = [] {
        auto loaded = maps::load_map("gen:rooms:1", maps::MapSearch{});
        if (!loaded) {
            throw std::runtime_error("gen:rooms:1: " + loaded.error().message());
        }
        return std::make_shared<const maps::Map>(std::move(loaded).value());
    }();
    return map;
}

/// Puts a lethal pit (an 80-unit cube of hazard) around spawn point `index` of `map` and
/// returns its centre: a player put there dies on its first step.
inline glm::vec3 add_pit_at_spawn(maps::Map& map, std::size_t index) {
    const glm::vec3 pit = map.spawn_points.at(index).origin;
    map.hazards.push_back(
        {visibility::Aabb{pit - glm::vec3(40.0f), pit + glm::vec3(40.0f)}, "test pit"});
    return pit;
}

} // namespace dsoc::testing
