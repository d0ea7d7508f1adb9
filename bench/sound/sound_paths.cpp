// dsoc-sound-paths: where players are on a map (the eyes of wandering bots, sampled
// every second of a minute), and for pairs of those places within earshot in a
// straight line (sim::SoundSettings: shots 1,330 units, footsteps 800, eye to eye), the
// length of the shortest path a sound would take through the map's air
// (maps/air_paths.hpp).
// Quake 3's mixer plays a sound by the straight line alone, through walls; this
// measures how many of the pairs it lets hear each other a path rule would silence:
//   pairs            ordered pairs of a listener (one of --listeners places) and any
//                    other place, within the range in a straight line (two listeners
//                    make two pairs, one each way: the same path)
//   path within      of those, the share whose air path is within the range too
//   median ratio     air path over straight line, median over the pairs (paths longer
//                    than twice the range count as twice the range)
//   over 1.5x        the share whose path is more than 1.5 times the straight line
// Deterministic for a seed; one line per map, or one JSON object per line (--json).

#include "dsoc/cli/program.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/interest/game_world.hpp"
#include "dsoc/maps/air_paths.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/sim/sounds.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace dsoc;

struct RangeFigures {
    std::size_t pairs = 0;
    std::size_t path_within = 0;
    std::size_t over_one_and_half = 0;
    std::vector<float> ratios;

    [[nodiscard]] double median_ratio() {
        if (ratios.empty()) {
            return 0.0;
        }
        auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
        std::nth_element(ratios.begin(), middle, ratios.end());
        return *middle;
    }
    [[nodiscard]] double share(std::size_t n) const {
        return pairs == 0 ? 0.0 : static_cast<double>(n) / static_cast<double>(pairs);
    }
};

void count(RangeFigures& f, float straight, float path, float range) {
    if (straight > range) {
        return;
    }
    ++f.pairs;
    f.path_within += path <= range ? 1 : 0;
    const float capped = std::min(path, 2.0f * range); // kNoAirPath: beyond the search
    const float ratio = straight > 0.0f ? capped / straight : 1.0f;
    f.ratios.push_back(ratio);
    f.over_one_and_half += ratio > 1.5f ? 1 : 0;
}

} // namespace

int main(int argc, char** argv) {
    std::vector<std::string> map_specs;
    float finest_voxel = 16.0f;
    double max_voxels = 16e6;
    int bots = 32;
    int listeners = 100;
    std::uint64_t seed = 1;
    bool json = false;
    CLI::App app{"dsoc-sound-paths: sound's path around walls against the straight line, between "
                 "places bots stand within earshot"};
    dsoc::cli::set_up(app, "dsoc-sound-paths");
    app.add_option("maps", map_specs,
                   "Maps (names, files or gen: specs; default: every map found)");
    dsoc::cli::add_setting(
        app, "--voxel", finest_voxel,
        "Edge of the air's voxels [world units], grown by a quarter at a time on a "
        "map that needs more than --max-voxels")
        ->check(CLI::Range(4.0f, 256.0f));
    dsoc::cli::add_setting(app, "--max-voxels", max_voxels, "Most voxels of a map's air grid")
        ->check(CLI::Range(1e5, 1e8));
    dsoc::cli::add_setting(app, "--bots", bots, "Wandering bots whose eyes are sampled")
        ->check(CLI::Range(1, 1000));
    dsoc::cli::add_setting(app, "--listeners", listeners,
                           "Sampled places a path search starts from")
        ->check(CLI::Range(1, 100000));
    dsoc::cli::add_setting(app, "--seed", seed, "Seed of the bots and of the listeners' draw");
    app.add_flag("--json", json, "One JSON object per map and line");
    if (const auto stop = cli::parse(app, argc, argv)) {
        return *stop;
    }
    const maps::MapSearch search = maps::MapSearch::from_environment();
    if (map_specs.empty()) {
        map_specs = maps::list_maps(search);
    }
    if (map_specs.empty()) {
        fmt::print(stderr, "dsoc-sound-paths: no maps found (install openarena-081-maps or set "
                           "DSOC_MAP_PATH)\n");
        return cli::exit_usage;
    }
    const sim::SoundSettings sounds;
    const float search_bound = 2.0f * std::max(sounds.shot_range, sounds.footstep_range);
    int failures = 0;
    if (!json) {
        fmt::print("| map | voxel | shot pairs | path within | median ratio | over 1.5x | "
                   "footstep pairs | path within | median ratio | over 1.5x | s |\n"
                   "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    }
    // Over every map: the pairs pooled, and the maps' medians.
    RangeFigures all_shots;
    RangeFigures all_steps;
    for (const std::string& spec : map_specs) {
        const auto start = std::chrono::steady_clock::now();
        auto loaded = maps::load_map(spec, search);
        if (!loaded) {
            fmt::print(stderr, "dsoc-sound-paths: {}\n",
                       cli::map_load_failure("map", spec, loaded.error().message()));
            ++failures;
            continue;
        }
        const auto map = std::make_shared<const maps::Map>(std::move(loaded).value());
        if (map->spawn_points.empty()) {
            fmt::print(stderr, "dsoc-sound-paths: {}: no spawn points\n", spec);
            ++failures;
            continue;
        }
        // The finest voxels within the budget (a path search's work grows with their
        // number; coarser voxels narrow openings and lengthen paths).
        float voxel = finest_voxel;
        const glm::vec3 extent = map->bounds.max - map->bounds.min + 4.0f * finest_voxel;
        while (static_cast<double>(extent.x / voxel) * (extent.y / voxel) * (extent.z / voxel) >
               max_voxels) {
            voxel *= 1.25f;
        }
        maps::AirGrid grid;
        try {
            grid = maps::air_grid(*map, voxel);
        } catch (const std::invalid_argument& e) {
            fmt::print(stderr, "dsoc-sound-paths: {}\n", e.what());
            ++failures;
            continue;
        }
        // Where players are: the bots' eyes, every second of a minute at 20 Hz.
        std::vector<glm::vec3> eyes;
        {
            interest::WorldSettings settings;
            settings.bots = bots;
            settings.seed = seed;
            interest::GameWorld world(settings, map);
            constexpr int kSteps = 20 * 60;
            for (int step = 1; step <= kSteps; ++step) {
                world.step(1.0f / 20.0f);
                if (step % 20 == 0) {
                    for (const interest::Entity& e : world.entities()) {
                        eyes.push_back(world.eye_of(e));
                    }
                }
            }
        }
        std::mt19937_64 rng(seed);
        std::shuffle(eyes.begin(), eyes.end(), rng);
        maps::AirPathSearch paths(grid);
        RangeFigures shots;
        RangeFigures steps;
        const std::size_t listening = std::min(eyes.size(), static_cast<std::size_t>(listeners));
        for (std::size_t i = 0; i < listening; ++i) {
            // Every other place within the longer range of this one.
            std::vector<glm::vec3> near;
            std::vector<float> straight;
            for (std::size_t j = 0; j < eyes.size(); ++j) {
                const float d = glm::length(eyes[j] - eyes[i]);
                if (j != i && d <= std::max(sounds.shot_range, sounds.footstep_range)) {
                    near.push_back(eyes[j]);
                    straight.push_back(d);
                }
            }
            if (near.empty()) {
                continue;
            }
            const std::vector<float> lengths = paths.lengths(eyes[i], near, search_bound);
            for (std::size_t k = 0; k < near.size(); ++k) {
                count(shots, straight[k], lengths[k], sounds.shot_range);
                count(steps, straight[k], lengths[k], sounds.footstep_range);
            }
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const std::size_t open = static_cast<std::size_t>(
            std::count(grid.solid.begin(), grid.solid.end(), std::uint8_t{0}));
        if (json) {
            const auto figures = [](RangeFigures& f, float range) {
                return nlohmann::json{{"range", range},
                                      {"pairs", f.pairs},
                                      {"path_within_share", f.share(f.path_within)},
                                      {"median_ratio", f.median_ratio()},
                                      {"over_1_5_share", f.share(f.over_one_and_half)}};
            };
            const nlohmann::json line{{"map", map->name},
                                      {"spec", spec},
                                      {"places", eyes.size()},
                                      {"listeners", listening},
                                      {"voxel", voxel},
                                      {"voxels", grid.solid.size()},
                                      {"open_voxels", open},
                                      {"shots", figures(shots, sounds.shot_range)},
                                      {"footsteps", figures(steps, sounds.footstep_range)},
                                      {"seconds", seconds}};
            fmt::print("{}\n", line.dump());
        } else {
            fmt::print("| {} | {:g} | {} | {:.1f}% | {:.2f} | {:.1f}% | {} | {:.1f}% | {:.2f} | "
                       "{:.1f}% | {:.1f} |\n",
                       map->name, voxel, shots.pairs, 100.0 * shots.share(shots.path_within),
                       shots.median_ratio(), 100.0 * shots.share(shots.over_one_and_half),
                       steps.pairs, 100.0 * steps.share(steps.path_within), steps.median_ratio(),
                       100.0 * steps.share(steps.over_one_and_half), seconds);
        }
        std::fflush(stdout);
        for (auto [all, one] : {std::pair{&all_shots, &shots}, std::pair{&all_steps, &steps}}) {
            all->pairs += one->pairs;
            all->path_within += one->path_within;
            all->over_one_and_half += one->over_one_and_half;
            if (one->pairs > 0) {
                all->ratios.push_back(static_cast<float>(one->median_ratio()));
            }
        }
    }
    if (!json && map_specs.size() > 1) {
        fmt::print("| **{} maps** (pairs pooled; the maps' median ratio) | | {} | {:.1f}% | {:.2f} "
                   "| {:.1f}% | {} | {:.1f}% | {:.2f} | {:.1f}% | |\n",
                   all_shots.ratios.size(), all_shots.pairs,
                   100.0 * all_shots.share(all_shots.path_within), all_shots.median_ratio(),
                   100.0 * all_shots.share(all_shots.over_one_and_half), all_steps.pairs,
                   100.0 * all_steps.share(all_steps.path_within), all_steps.median_ratio(),
                   100.0 * all_steps.share(all_steps.over_one_and_half));
    }
    return failures == 0 ? cli::exit_ok : cli::exit_failure;
}
