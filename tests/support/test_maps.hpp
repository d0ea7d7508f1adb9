#pragma once
// Maps for tests: small generated worlds that need no files, loaded once per process.

#include "dsoc/maps/map_source.hpp"

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

} // namespace dsoc::testing
