#pragma once
// Where the tests find the OpenArena maps (Debian's openarena-081-maps, which
// scripts/setup installs), and the skip of a test that needs them when they are not.

#include "dsoc/maps/map_source.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dsoc::testing {

/// The pk3 holding the OpenArena maps (oa_dm4 and the others).
inline const std::filesystem::path kOpenArenaPak =
    std::filesystem::path(maps::kOpenArenaBaseDir) / "pak1-maps.pk3";

} // namespace dsoc::testing

/// Skips the running test (returns from it) when kOpenArenaPak is not installed.
#define DSOC_REQUIRE_OPENARENA()                                                                   \
    do {                                                                                           \
        if (!std::filesystem::exists(::dsoc::testing::kOpenArenaPak)) {                            \
            GTEST_SKIP() << "OpenArena maps not installed (" << ::dsoc::testing::kOpenArenaPak     \
                         << " missing; scripts/setup installs openarena-081-maps)";                \
        }                                                                                          \
    } while (false)
