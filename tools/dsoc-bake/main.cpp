// dsoc-bake: bakes the cell visibility table of each map into the cache directory (or
// loads it when a good one is there) and prints what it holds. Progress with an ETA
// goes to stderr.
// Exit status (dsoc/cli/program.hpp): 0 every map baked or loaded, 1 some map failed
// (message on stderr), 2 bad usage.

#include "dsoc/cli/program.hpp"
#include "dsoc/cli/progress.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/interest/bake_request.hpp"
#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/visibility/cell_block_unions.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <sys/resource.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <limits>

namespace {

/// User and system CPU time of the whole process so far (every thread). [Units: s]
double process_cpu_seconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const auto seconds = [](const timeval& t) {
        return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
    };
    return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

/// The process's peak resident memory so far (over every map of the run). [Units: bytes]
std::uint64_t peak_rss_bytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024; // ru_maxrss is in KiB
}

/// Set by SIGINT or SIGTERM: the bake saves where it stands and stops. (Lock-free, so
/// a signal handler may store it and the bake's threads read it.)
std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free);

extern "C" void request_stop(int /*signal*/) {
    g_stop_requested.store(true, std::memory_order_relaxed);
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "Bakes the cell visibility table of each map (cached; see docs/baked-visibility.md)"};
    dsoc::cli::set_up(app, "dsoc-bake");
    std::vector<std::string> specs;
    // The request the server and the evaluation make, so that they find this table.
    dsoc::maps::BakeRequest request = dsoc::interest::walking_bake_request();
    bool whole_box = false;
    std::string dir;
    bool json = false;
    std::uint64_t max_mib = dsoc::maps::BakeRequest{}.max_table_bytes >> 20;
    app.add_option("maps", specs, "map names (oa_dm4), .bsp/.pk3/text map paths or gen:...")
        ->required();
    dsoc::cli::add_setting(app, "--cell-size", request.config.cell_size,
                           "cell edge in world units");
    dsoc::cli::add_setting(app, "--threads", request.config.threads,
                           "worker threads (0: one per core)");
    dsoc::cli::add_setting(app, "--portal-depth", request.config.portal_depth,
                           "portal levels of the exact tests");
    dsoc::cli::add_setting(app, "--top-level", request.config.top_level,
                           "hierarchy levels (blocks of 2^L cells paired first; 0: none)");
    dsoc::cli::add_setting(app, "--witness-stop-level", request.config.witness_stop_level,
                           "a clear segment between blocks of 2^L cells marks them all visible");
    dsoc::cli::add_setting(app, "--witness-segments", request.config.witness_segments,
                           "segments cast between two blocks before an exact test");
    app.add_flag("--both-directions,!--one-direction", request.config.both_directions,
                 "retry a failed exact test of two cells with region and box swapped")
        ->capture_default_str();
    dsoc::cli::add_setting(app, "--max-table-mib", max_mib,
                           "cells grow until the dense rows the bake fills fit this many MiB");
    app.add_option("--cache-dir", dir,
                   "where tables are kept (default: $DSOC_BAKE_DIR, "
                   "$XDG_CACHE_HOME/dsoc/bakes or ~/.cache/dsoc/bakes)");
    app.add_flag("--force", request.force,
                 "bake again even when the cache holds a good table (and do not go on from a "
                 "partial bake)");
    double max_minutes = request.max_bake_seconds / 60.0;
    dsoc::cli::add_setting(app, "--max-bake-minutes", max_minutes,
                           "cells grow until a bake is predicted (from a sample of its pairs) "
                           "to take at most this long on a quiet machine (0: no limit)");
    dsoc::cli::add_setting(app, "--checkpoint-seconds", request.checkpoint_seconds,
                           "save where the bake stands this often, so that it goes on after a "
                           "restart (0: never)");
    app.add_flag("--whole-box", whole_box,
                 "cover every open cell of the map's box, not only where walkers can be "
                 "(a table the server does not look for)");
    app.add_flag("--json", json, "one JSON object per map on stdout");
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }
    if (const auto problems = dsoc::visibility::validate(request.config); !problems.empty()) {
        std::cerr << "dsoc-bake: " << problems.front() << "\n";
        return dsoc::cli::exit_usage;
    }
    request.dir = dir;
    request.max_table_bytes = max_mib << 20;
    if (!(max_minutes >= 0.0)) {
        std::cerr << "dsoc-bake: --max-bake-minutes must be >= 0\n";
        return dsoc::cli::exit_usage;
    }
    request.max_bake_seconds =
        max_minutes > 0.0 ? max_minutes * 60.0 : std::numeric_limits<double>::infinity();
    if (whole_box) {
        request.player_space.reset();
    }

    // Ctrl-C or a TERM during a bake keeps its partial file, so the next run goes on.
    std::signal(SIGINT, request_stop);
    std::signal(SIGTERM, request_stop);
    request.stop = [] { return g_stop_requested.load(std::memory_order_relaxed); };
    const auto search = dsoc::maps::MapSearch::from_environment();
    int failures = 0;
    for (const std::string& spec : specs) {
        auto map = dsoc::maps::load_map(spec, search);
        if (!map) {
            std::cerr << "dsoc-bake: "
                      << dsoc::cli::map_load_failure("maps", spec, map.error().message()) << "\n";
            ++failures;
            continue;
        }
        const auto scene = dsoc::visibility::OccluderScene::build(map->occluders);
        dsoc::cli::ProgressLine progress(map->name);
        request.gave_up = [&](const dsoc::maps::GridOverBudget& over) {
            progress.restart();
            std::cerr << "dsoc-bake: " << map->name << ": " << dsoc::maps::describe(over)
                      << ": coarser cells instead" << std::endl;
        };
        const double cpu_before = process_cpu_seconds();
        auto baked = dsoc::maps::load_or_bake(map.value(), *scene, request,
                                              [&](double f, double s) { progress(f, s); });
        const double cpu_seconds = process_cpu_seconds() - cpu_before;
        if (!baked) {
            std::cerr << "dsoc-bake: " << baked.error().message() << "\n";
            ++failures;
            if (g_stop_requested.load()) {
                break; // the maps after it are not started
            }
            continue;
        }
        if (!baked->cache_problem.empty()) {
            std::cerr << "dsoc-bake: cached table refused: " << baked->cache_problem << "\n";
        }
        if (!baked->write_problem.empty()) {
            std::cerr << "dsoc-bake: table not saved: " << baked->write_problem << "\n";
        }
        const auto& t = *baked->table;
        const auto& s = baked->stats;
        const double n = static_cast<double>(t.open_count());
        const double hidden = n > 0 ? static_cast<double>(t.hidden_pairs()) / (n * n) : 0.0;
        std::error_code ec;
        const auto file_bytes = std::filesystem::file_size(baked->file, ec);
        // What a culler holds beside the table at run time (made where it is loaded).
        const std::size_t block_union_bytes = dsoc::visibility::CellBlockUnions(t).memory_bytes();
        if (json) {
            nlohmann::json out;
            out["map"] = map->name;
            out["spec"] = spec; // as given on the command line
            out["file"] = baked->file.string();
            out["from_cache"] = baked->from_cache;
            out["cell_size"] = t.grid().cell_size;
            out["cells"] = t.grid().cell_count();
            out["open_cells"] = t.open_count();
            out["uncovered_cells"] = t.uncovered_cells().size();
            out["hidden_pair_fraction"] = hidden;
            out["file_bytes"] = ec ? 0 : file_bytes;
            out["memory_bytes"] = t.memory_bytes();
            out["block_union_bytes"] = block_union_bytes;
            out["bake_seconds"] = s.seconds;
            out["cpu_seconds"] = cpu_seconds; // every thread's, loading or baking
            out["peak_rss_bytes"] = peak_rss_bytes();
            out["exact_tests"] = s.exact_tests;
            out["exact_hidden"] = s.exact_hidden;
            out["pruned"] = s.pruned;
            out["witness_rays"] = s.witness_rays;
            out["witness_clear"] = s.witness_clear;
            out["resumed_fraction"] = baked->resumed_fraction;
            out["predicted_seconds"] = s.predicted_seconds; // 0: none made
            auto& over = out["over_budget"] = nlohmann::json::array();
            for (const auto& o : baked->over_budget) {
                over.push_back({{"cell_size", o.cell_size},
                                {"predicted_seconds", o.predicted_seconds},
                                {"spent_seconds", o.spent_seconds}});
            }
            std::cout << out.dump() << std::endl;
        } else {
            std::printf("%s: %s %s\n", map->name.c_str(), baked->from_cache ? "loaded" : "baked",
                        baked->file.c_str());
            std::printf("  cells %zu (%.0f-unit), open %zu (and %zu uncovered), hidden pairs "
                        "%.1f%%, file %.1f MiB, memory %.1f MiB (and %.1f MiB of block unions "
                        "at run time)\n",
                        t.grid().cell_count(), static_cast<double>(t.grid().cell_size),
                        t.open_count(), t.uncovered_cells().size(), 100.0 * hidden,
                        ec ? 0.0 : static_cast<double>(file_bytes) / (1 << 20),
                        static_cast<double>(t.memory_bytes()) / (1 << 20),
                        static_cast<double>(block_union_bytes) / (1 << 20));
            if (baked->resumed_fraction > 0.0) {
                std::printf("  went on from a partial bake %.1f%% done (the bake's time counts "
                            "every run, the CPU this one)\n",
                            100.0 * baked->resumed_fraction);
            }
            if (!baked->from_cache) {
                std::printf("  bake %.1f s (%.1f s of CPU): %llu pair visits, %llu pruned by the "
                            "PVS, %llu witness rays (%llu clear), %llu exact tests (%llu hidden)\n",
                            s.seconds, cpu_seconds, static_cast<unsigned long long>(s.pair_visits),
                            static_cast<unsigned long long>(s.pruned),
                            static_cast<unsigned long long>(s.witness_rays),
                            static_cast<unsigned long long>(s.witness_clear),
                            static_cast<unsigned long long>(s.exact_tests),
                            static_cast<unsigned long long>(s.exact_hidden));
                std::printf("  exact tests (hidden) by block level:");
                for (int l = 0; l < 7; ++l) {
                    if (s.exact_by_level[l] > 0) {
                        std::printf(" %d: %llu (%llu)", l,
                                    static_cast<unsigned long long>(s.exact_by_level[l]),
                                    static_cast<unsigned long long>(s.hidden_by_level[l]));
                    }
                }
                std::printf("\n");
            }
            std::fflush(stdout);
        }
    }
    return failures == 0 ? dsoc::cli::exit_ok : dsoc::cli::exit_failure;
}
