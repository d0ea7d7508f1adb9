// A stop asked for while the server starts (startup_stop.hpp): Ctrl-C or SIGTERM during
// the first bake of a map's table saves the partial bake at once and gives up, so the
// next start goes on from it.

#include "dsoc/interest/game_world.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/startup_stop.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace dsoc::server {
namespace {

/// Exit status of the child: 0 when the signal stopped the bake with its partial file
/// saved, else which check failed.
[[noreturn]] void bake_after_a_signal(const std::filesystem::path& dir, int signal) {
    catch_startup_signals();
    if (startup_stop_requested()) {
        std::exit(10);
    }
    std::raise(signal);
    if (!startup_stop_requested()) {
        std::exit(11);
    }
    ServerConfig config;
    config.bots = 0;
    config.bake_dir = dir.string();
    config.bake_cell_size = 24.0f; // minutes of work: only the stop ends it soon
    const interest::GameWorld world(world_settings(config), testing::rooms_map());
    const auto scene = visibility::OccluderScene::build(world.map().occluders);
    try {
        (void)baked_table(config, world, *scene);
    } catch (const std::runtime_error& e) {
        const std::string what = e.what();
        bool partial = false;
        for (const auto& entry : std::filesystem::directory_iterator(dir)) {
            partial = partial || entry.path().extension() == ".partial";
        }
        std::exit(what.find("bake stopped at") != std::string::npos && partial ? 0 : 12);
    }
    std::exit(13); // baked to the end
}

TEST(StartupStop, ASignalDuringTheFirstBakeSavesItAndGivesUp) {
    // The child runs this binary again from the start rather than a fork of this process,
    // which may hold the threads of earlier tests (ThreadSanitizer refuses to start
    // threads in a fork of a threaded process, and the bake starts some).
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    for (const int signal : {SIGINT, SIGTERM}) {
        const auto dir = std::filesystem::temp_directory_path() /
                         ("dsoc-startup-stop-" + std::to_string(signal));
        std::filesystem::remove_all(dir);
        std::filesystem::create_directories(dir);
        // In a child process: the flag stays set for the rest of the process.
        EXPECT_EXIT(bake_after_a_signal(dir, signal), ::testing::ExitedWithCode(0), "")
            << "signal " << signal;
        std::filesystem::remove_all(dir);
    }
}

} // namespace
} // namespace dsoc::server
