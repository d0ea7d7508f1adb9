#include "dsoc/maps/bake_cache.hpp"

#include "dsoc/maps/bake_partial.hpp"
#include "dsoc/maps/pvs_bake_pruner.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace dsoc::maps {

namespace {

/// Thrown by a save when the request's stop() says so: ends the bake between pairs.
struct BakeStopped {
    double fraction;
    bool saved; ///< the partial file was written
};

std::string file_stem(const std::string& name) {
    std::string out;
    for (const char c : name) {
        out += std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' ? c : '_';
    }
    return out.empty() ? std::string("map") : out.substr(0, 64);
}

} // namespace

std::filesystem::path default_bake_dir() {
    if (const char* dir = std::getenv("DSOC_BAKE_DIR"); dir != nullptr && *dir != '\0') {
        return dir;
    }
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
        return std::filesystem::path(xdg) / "dsoc" / "bakes";
    }
    if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
        return std::filesystem::path(home) / ".cache" / "dsoc" / "bakes";
    }
    return ".dsoc-bakes";
}

std::string describe(const GridOverBudget& over) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "%g-unit cells: the bake would need about %.0f s more of a quiet machine, "
                  "over the %.0f s budget (given up after %.0f s)",
                  static_cast<double>(over.cell_size), over.predicted_seconds, over.budget_seconds,
                  over.spent_seconds);
    return line;
}

static std::unique_ptr<PvsBakePruner> pvs_pruner(const Map& map) {
    if (map.pvs != nullptr && map.pvs->has_visibility()) {
        return std::make_unique<PvsBakePruner>(map.pvs);
    }
    return nullptr;
}

/// The coarsest grid a bake may use: the first whose cells are past 1024 units. It is
/// baked whatever it costs (no memory or time budget applies to it).
static bool is_last_grid(float cell_size) {
    return cell_size > 1024.0f;
}

/// The grids a bake may use, finest first: cells grow by 1.25x from `cell_size`;
/// grids of too many cells to even look at are skipped; the first past 1024 units is
/// the last. Calls `take(grid, last)` until it returns true; returns that grid.
template <class Take>
visibility::CellGrid first_grid(const Map& map, float cell_size, Take take) {
    for (;; cell_size *= 1.25f) {
        const auto grid =
            visibility::CellGrid::covering(map.bounds.expanded(kBakeGridMargin), cell_size);
        const bool last = is_last_grid(cell_size);
        if (grid.cell_count() > kMaxBakeGridCells && !last) {
            continue;
        }
        if (take(grid, last)) {
            return grid;
        }
    }
}

/// One byte per cell of `grid`: whether `space` covers it (empty: no space, all).
static std::vector<std::uint8_t> covered_cells(const visibility::CellGrid& grid,
                                               const std::vector<visibility::Aabb>* space_boxes) {
    return space_boxes != nullptr ? cells_meeting(grid, *space_boxes) : std::vector<std::uint8_t>{};
}

visibility::CellGrid bake_grid(const Map& map, const visibility::OccluderScene& scene,
                               float cell_size, std::uint64_t max_table_bytes,
                               const std::optional<PlayerSpace>& space) {
    const auto pruner = pvs_pruner(map);
    const auto boxes = space ? player_space_boxes(map, *space) : std::vector<visibility::Aabb>{};
    // The first grid the reader accepts whose dense table of open cells fits the budget.
    return first_grid(map, cell_size, [&](const visibility::CellGrid& grid, bool last) {
        const auto covered = covered_cells(grid, space ? &boxes : nullptr);
        const auto open = static_cast<std::uint64_t>(
            visibility::split_covered(visibility::open_cells_of(scene, grid, pruner.get()), covered)
                .first.size());
        const bool readable =
            grid.cell_count() <= kMaxBakeCellsPerOpenCell * std::max<std::uint64_t>(open, 64);
        return (readable && open * ((open + 63) / 64) * 8 <= max_table_bytes) || last;
    });
}

/// Bakes `out.file`'s table over `grid` (or loads it when a good file is there: then
/// out.table is set). Nothing when the bake would be over the request's time budget
/// (recorded in out.over_budget; never on the last grid, which is baked whatever it
/// takes); an error when the request's stop() ended it.
static Result<std::optional<visibility::CellVisibilityTable>>
bake_one_grid(const Map& map, const visibility::OccluderScene& scene,
              const visibility::CellGrid& grid, const BakeRequest& request,
              const visibility::BakePruner* pruner, const std::vector<std::uint8_t>& covered,
              const visibility::BakeProgress& progress, BakedTable& out) {
    std::error_code ec;
    const auto note_problem = [&](const std::string& problem) {
        out.cache_problem += (out.cache_problem.empty() ? "" : "; ") + problem;
    };
    out.resumed_fraction = 0.0;
    out.write_problem.clear(); // a grid given up before may have left one
    if (!request.force && std::filesystem::exists(out.file, ec)) {
        auto cached = read_bake_file(out.file, out.key);
        if (cached) {
            out.table =
                std::make_shared<const visibility::CellVisibilityTable>(std::move(cached).value());
            out.from_cache = true;
            return std::optional<visibility::CellVisibilityTable>{};
        }
        note_problem(cached.error().message() + "; baking again");
    }
    // A bake stopped part way (a restart) goes on from its partial file.
    const auto partial_file = partial_file_of(out.file);
    std::optional<PartialBake> partial;
    if (!request.force && std::filesystem::exists(partial_file, ec)) {
        auto read = read_partial_file(partial_file, out.key);
        if (read) {
            partial = std::move(read).value();
        } else {
            note_problem(read.error().message() + "; baking from the start");
        }
    }
    visibility::BakeState resume;
    visibility::BakeCheckpoints checkpoints;
    // A stop ends the bake between pairs even when nothing is saved (no checkpoints,
    // or a partial file that cannot be written).
    if (request.checkpoint_seconds > 0.0 || request.stop) {
        checkpoints.interval_seconds = request.checkpoint_seconds > 0.0
                                           ? request.checkpoint_seconds
                                           : std::numeric_limits<double>::infinity();
        checkpoints.save_now = request.stop;
        checkpoints.save = [&](const visibility::BakeState& state) {
            bool saved = false;
            if (request.checkpoint_seconds > 0.0) {
                if (auto problem = write_partial_file(partial_file, state, out.key)) {
                    out.write_problem = *problem;
                } else {
                    saved = true;
                }
            }
            if (request.stop && request.stop()) {
                throw BakeStopped{state.pairs_total > 0 ? static_cast<double>(state.pairs_done) /
                                                              static_cast<double>(state.pairs_total)
                                                        : 0.0,
                                  saved};
            }
        };
    }
    if (partial) {
        resume = partial->state();
        checkpoints.resume = &resume;
        out.resumed_fraction = resume.pairs_total > 0 ? static_cast<double>(resume.pairs_done) /
                                                            static_cast<double>(resume.pairs_total)
                                                      : 0.0;
    }
    visibility::BakeBudget budget;
    if (!is_last_grid(grid.cell_size)) {
        budget.max_seconds = request.max_bake_seconds;
        budget.sample_fraction = request.budget_sample_fraction;
        budget.cpu_seconds = request.budget_clock;
    }
    const auto bake = [&] {
        return visibility::bake_cell_visibility(scene, grid, request.config, pruner, &out.stats,
                                                progress, covered, checkpoints, budget);
    };
    try {
        try {
            return std::optional<visibility::CellVisibilityTable>{bake()};
        } catch (const std::invalid_argument& e) {
            if (checkpoints.resume == nullptr) {
                throw;
            }
            // Checksummed and of this key, yet not of this bake's size: never trusted.
            note_problem(partial_file.string() + ": " + e.what() + "; baking from the start");
            checkpoints.resume = nullptr;
            out.resumed_fraction = 0.0;
            return std::optional<visibility::CellVisibilityTable>{bake()};
        }
    } catch (const BakeStopped& stopped) {
        char done[32];
        std::snprintf(done, sizeof done, "%.1f%%", 100.0 * stopped.fraction);
        return LoadError{map.name, "",
                         std::string("bake stopped at ") + done + "; " +
                             (stopped.saved
                                  ? partial_file.string() + " goes on from there next time"
                              : request.checkpoint_seconds > 0.0
                                  ? "nothing kept: " + out.write_problem
                                  : std::string("nothing kept (checkpoint_seconds is 0)"))};
    } catch (const visibility::BakeOverBudget& over) {
        // A state this bake saved holds no more than its sample: of no use. One it
        // went on from is kept (a later bake with a larger budget may finish it).
        if (checkpoints.resume == nullptr) {
            std::filesystem::remove(partial_file, ec);
        }
        out.over_budget.push_back(
            {grid.cell_size, over.predicted_seconds, over.spent_seconds, request.max_bake_seconds});
        if (request.gave_up) {
            request.gave_up(out.over_budget.back());
        }
        return std::optional<visibility::CellVisibilityTable>{};
    }
}

Result<BakedTable> load_or_bake(const Map& map, const visibility::OccluderScene& scene,
                                const BakeRequest& request,
                                const visibility::BakeProgress& progress) {
    if (map.bounds.is_empty()) {
        return LoadError{map.name, "", "the map has no bounds: nothing to bake"};
    }
    if (const auto problems = visibility::validate(request.config); !problems.empty()) {
        return LoadError{map.name, "bake settings", problems.front()};
    }
    if (!(request.max_bake_seconds > 0.0)) {
        return LoadError{map.name, "bake settings", "max_bake_seconds must be > 0"};
    }
    if (!(request.budget_sample_fraction > 0.0 && request.budget_sample_fraction <= 1.0)) {
        return LoadError{map.name, "bake settings", "budget_sample_fraction must be within (0, 1]"};
    }
    if (request.player_space) {
        if (const auto problems = validate(*request.player_space); !problems.empty()) {
            return LoadError{map.name, "player space", problems.front()};
        }
    }
    BakedTable out;
    const auto dir = request.dir.empty() ? default_bake_dir() : request.dir;
    const auto file_of = [&](std::uint64_t key) {
        char key_hex[17];
        std::snprintf(key_hex, sizeof key_hex, "%016llx", static_cast<unsigned long long>(key));
        return dir / (file_stem(map.name) + "-" + key_hex + ".dsocbake");
    };
    const std::uint64_t key_of_map = bake_key_of_map(map);
    std::error_code ec;
    if (!request.force) {
        // A good table already baked for one of the grids a bake may use (the finest
        // first) is taken without deciding which grid a bake would pick now: that
        // counts the open cells of every finer grid, seconds on a large map.
        bool found = false;
        (void)first_grid(map, request.config.cell_size,
                         [&](const visibility::CellGrid& grid, bool last) {
                             const std::uint64_t key =
                                 bake_key(key_of_map, grid, request.config, request.player_space);
                             const auto file = file_of(key);
                             if (!std::filesystem::exists(file, ec)) {
                                 return last;
                             }
                             auto cached = read_bake_file(file, key);
                             if (!cached) {
                                 return last; // reported below if it is the grid a bake picks
                             }
                             out.key = key;
                             out.file = file;
                             out.table = std::make_shared<const visibility::CellVisibilityTable>(
                                 std::move(cached).value());
                             out.from_cache = true;
                             found = true;
                             return true;
                         });
        if (found) {
            return out;
        }
    }
    // The compiler's PVS, where the map has one, proves far pairs apart for free.
    const auto pruner = pvs_pruner(map);
    const auto boxes = request.player_space ? player_space_boxes(map, *request.player_space)
                                            : std::vector<visibility::Aabb>{};
    std::optional<visibility::CellVisibilityTable> baked;
    // The grid the memory budget picks, then coarser ones while a bake would be over
    // the time budget.
    for (float cell_size = request.config.cell_size; !baked;) {
        const auto grid =
            bake_grid(map, scene, cell_size, request.max_table_bytes, request.player_space);
        out.key = bake_key(key_of_map, grid, request.config, request.player_space);
        out.file = file_of(out.key);
        auto one = bake_one_grid(map, scene, grid, request, pruner.get(),
                                 covered_cells(grid, request.player_space ? &boxes : nullptr),
                                 progress, out);
        if (!one) {
            return std::move(one).error();
        }
        if (out.table != nullptr) {
            return out; // from the cache
        }
        baked = std::move(one).value();
        cell_size = grid.cell_size * 1.25f;
        if (!baked && request.stop && request.stop()) {
            char size[32];
            std::snprintf(size, sizeof size, "%g", static_cast<double>(cell_size));
            return LoadError{map.name, "",
                             std::string("bake stopped before trying ") + size +
                                 "-unit cells (the finer ones were over the time budget)"};
        }
    }
    auto& table = *baked;
    if (auto problem = write_bake_file(out.file, table, out.key)) {
        out.write_problem = *problem;
    } else {
        std::filesystem::remove(partial_file_of(out.file), ec);
    }
    out.table = std::make_shared<const visibility::CellVisibilityTable>(std::move(table));
    return out;
}

} // namespace dsoc::maps
