#pragma once
// Baked cell visibility tables kept on disk between runs: a map's table is looked up
// by its key (bake_file.hpp) in a cache directory; a missing file is baked and
// written; a stale, truncated or corrupt one is reported in one line and rebaked,
// never trusted.

#include "dsoc/maps/bake_file.hpp"
#include "dsoc/maps/map.hpp"
#include "dsoc/maps/player_space.hpp"
#include "dsoc/visibility/cell_bake.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::maps {

/// $DSOC_BAKE_DIR, else $XDG_CACHE_HOME/dsoc/bakes, else $HOME/.cache/dsoc/bakes, else
/// ".dsoc-bakes" in the working directory.
[[nodiscard]] std::filesystem::path default_bake_dir();

/// A grid a bake gave up on because it would have taken longer than the request's
/// max_bake_seconds.
struct GridOverBudget {
    float cell_size = 0.0f;         ///< [Units: world units]
    double predicted_seconds = 0.0; ///< of the pairs it had left, as the budget counts them
    double spent_seconds = 0.0;     ///< on the sample, as the budget counts them
    double budget_seconds = 0.0;    ///< the request's max_bake_seconds
};

/// One line for a log: "62.5-unit cells: the bake would need about 650 s more of a
/// quiet machine, over the 540 s budget (given up after 5 s)".
[[nodiscard]] std::string describe(const GridOverBudget& over);

struct BakeRequest {
    visibility::CellBakeConfig config;
    /// Cache directory; empty: default_bake_dir().
    std::filesystem::path dir;
    /// The dense rows the bake fills must fit this; cells grow by 1.25x steps from
    /// config.cell_size until they do. (The table kept in memory after the bake, and
    /// after loading, has compressed rows: a fraction of this.) [Units: bytes]
    /// [Limit: >= 1 MiB]
    std::uint64_t max_table_bytes = std::uint64_t{128} << 20;
    /// A bake predicted to take longer than this is given up after a sample of its
    /// pairs (visibility::BakeBudget), and the cells grow by another 1.25x step; the
    /// grid past 1024 units is baked whatever it takes. Infinity: no limit. Nine
    /// minutes: a tenth below ten, for the prediction's error and the sample's work.
    /// [Units: s of CPU per worker thread: the wall time on an otherwise quiet machine]
    /// [Limit: > 0]
    double max_bake_seconds = 540.0;
    /// The share of a bake's pairs its time is predicted from. [Limit: (0, 1]]
    double budget_sample_fraction = 0.01;
    /// The CPU clock the budget reads (visibility::BakeBudget::cpu_seconds; tests set
    /// it); empty: the process's.
    std::function<double()> budget_clock;
    /// Called at once (on the calling thread) for each grid given up for the time
    /// budget, before the next is tried; BakedTable::over_budget lists them all too.
    std::function<void(const GridOverBudget&)> gave_up;
    /// Bake again even when a good file exists (a partial bake is not taken up either).
    bool force = false;
    /// A bake saves where it stands this often, in a partial file beside the table's
    /// (bake_partial.hpp), and a later bake of the same key goes on from there; the
    /// file is removed once the table is written. 0: no partial file. [Units: s]
    /// [Limit: >= 0]
    double checkpoint_seconds = 120.0;
    /// Asked every few milliseconds while the bake runs (thread-safe): true saves the
    /// partial file at once (with checkpoint_seconds > 0) and ends the bake there,
    /// kept for the next one; load_or_bake() then answers an error saying so.
    std::function<bool()> stop;
    /// Where the table must answer (its covered cells); the other open cells are left
    /// uncovered (no row, no answer). Nothing: the whole map's box.
    std::optional<PlayerSpace> player_space;
};

struct BakedTable {
    std::shared_ptr<const visibility::CellVisibilityTable> table;
    std::filesystem::path file;
    std::uint64_t key = 0;
    bool from_cache = false;
    /// Why an existing file was not used (one line); empty when none was refused.
    std::string cache_problem;
    /// Why the new table could not be written (one line); the table is still usable.
    std::string write_problem;
    /// The share of the bake's top pairs a partial file had already resolved (0: it
    /// started from the beginning).
    double resumed_fraction = 0.0;
    visibility::CellBakeStats stats; ///< of the bake, when one ran
    /// The finer grids given up on for the time budget, finest first.
    std::vector<GridOverBudget> over_budget;
};

/// How far the baked grid reaches past the map's bounds. The reachable eye region of a
/// walker pressed against an outer wall is a box that pokes through the wall; a grid
/// that ends at the wall cannot answer for it, and then the exact stages must. Cells
/// out there are covered only within the player space's margin of a floor; the rest
/// are uncovered (no row).
/// [Units: world units]
inline constexpr float kBakeGridMargin = 128.0f;

/// The grid `map` is baked over: cells of `cell_size` over the map's bounds grown by
/// kBakeGridMargin on every side, grown by
/// 1.25x steps until the dense rows of its open covered cells (all open cells when
/// `space` is nothing) fit `max_table_bytes`. (load_or_bake() grows them further when
/// a bake over this grid would be over its time budget.)
[[nodiscard]] visibility::CellGrid bake_grid(const Map& map, const visibility::OccluderScene& scene,
                                             float cell_size, std::uint64_t max_table_bytes,
                                             const std::optional<PlayerSpace>& space);

/// The table for `map` from the cache, or baked (and written) when there is no good
/// file. A good file for any grid a bake may use (bake_grid()'s candidates, the finest
/// first) is taken, even when `max_table_bytes` would now pick a coarser grid: the
/// budget bounds a bake's memory, and the cached table is already baked. `scene` must be built from
/// map.occluders. An error only when the map has no bounds or the settings are invalid.
[[nodiscard]] Result<BakedTable> load_or_bake(const Map& map,
                                              const visibility::OccluderScene& scene,
                                              const BakeRequest& request,
                                              const visibility::BakeProgress& progress = {});

} // namespace dsoc::maps
