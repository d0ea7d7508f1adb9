#pragma once
// Baking a CellVisibilityTable from an occluder scene: the exact from-region tests of
// the shaft stage (one occluder, fused occluders on cut planes, portals) applied to
// pairs of cells and of blocks of cells, so that one proof for two blocks hides every
// pair of their cells.
//
// Conservative by construction: a pair of cells is left hidden only when an exact test
// proved every segment between blocks holding them blocked, or the pruner proved them
// apart; every pair nothing proved is marked visible.

#include "dsoc/visibility/cell_visibility.hpp"
#include "dsoc/visibility/occluder_region_visibility.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace dsoc::visibility {

/// A cheap conservative proof the bake tries before its exact tests, e.g. the map
/// compiler's PVS. keys() says what the pruner knows of a box; hidden() is true only
/// when no point of a box with keys `a` can see any point of a box with keys `b`
/// (empty keys: nothing known, never hidden). Const and thread-safe.
class BakePruner {
public:
    virtual ~BakePruner() = default;
    /// True only when no eye and no point that can be seen lies in `box` (solid, or
    /// outside the map): such a cell gets no row.
    [[nodiscard]] virtual bool empty_space(const Aabb& /*box*/) const { return false; }
    virtual void keys(const Aabb& box, std::vector<std::int32_t>& out) const = 0;
    [[nodiscard]] virtual bool hidden(std::span<const std::int32_t> a,
                                      std::span<const std::int32_t> b) const = 0;
};

struct CellBakeConfig {
    /// Edge of a cell. [Units: world units] [Limit: 4 .. 1024]
    float cell_size = 32.0f;
    /// Worker threads; 0: one per core. [Limit: 0 .. 256]
    int threads = 0;
    /// Levels of portal tests in the exact stage (ShaftOcclusion). [Limit: 0 .. 4]
    int portal_depth = 2;
    /// Blocks of 2^top_level cells per side are paired first, then refined where no
    /// proof holds; 0 pairs single cells directly (no hierarchy: the slow twin the
    /// tests compare with). [Limit: 0 .. 6]
    int top_level = 2;
    /// When a segment between two blocks of at most 2^witness_stop_level cells per
    /// side is clear, every pair of their cells is marked visible without refining
    /// (0: refine to single cells, the tightest table). [Limit: 0 .. 3]
    int witness_stop_level = 0;
    /// Segments cast between two blocks (the first joins their representative
    /// points, the others random open points of random open cells of theirs) before
    /// an exact test: one
    /// clear segment shows the pair is not all hidden, for far less than a failed
    /// exact test. [Limit: 1 .. 64]
    int witness_segments = 4;
    /// After a failed exact test of two single cells, try it the other way round
    /// (region and box swapped): the tests are not symmetric in what they prove.
    bool both_directions = false;
};

/// Every problem with the settings, in words; empty when they are usable.
[[nodiscard]] std::vector<std::string> validate(const CellBakeConfig& config);

struct CellBakeStats {
    std::uint64_t cells = 0;           ///< grid cells
    std::uint64_t open_cells = 0;      ///< of those, not inside an occluder, and covered
    std::uint64_t uncovered_cells = 0; ///< open but not covered: no row
    std::uint64_t pair_visits = 0;     ///< pairs of blocks or cells looked at
    std::uint64_t pruned = 0;          ///< hidden by the pruner
    std::uint64_t witness_rays = 0;    ///< segments cast between blocks
    std::uint64_t witness_clear = 0;   ///< of those, clear (the pair is not all hidden)
    std::uint64_t exact_tests = 0;     ///< exact region tests
    std::uint64_t exact_hidden = 0;    ///< of those, proven hidden
    /// Exact tests and proofs by the higher level of the two blocks (0: two cells).
    std::uint64_t exact_by_level[7] = {};
    std::uint64_t hidden_by_level[7] = {};
    double seconds = 0.0;
    /// What BakeBudget's sample predicted for the pairs this run had left (all of
    /// them, unless it went on from a saved state), in its units (0: no prediction:
    /// no budget).
    double predicted_seconds = 0.0;

    /// Adds the work counts of `other` (pair visits to proofs by level); the cell
    /// counts, the seconds and the prediction are left as they are.
    CellBakeStats& add_work(const CellBakeStats& other) {
        pair_visits += other.pair_visits;
        pruned += other.pruned;
        witness_rays += other.witness_rays;
        witness_clear += other.witness_clear;
        exact_tests += other.exact_tests;
        exact_hidden += other.exact_hidden;
        for (int l = 0; l < 7; ++l) {
            exact_by_level[l] += other.exact_by_level[l];
            hidden_by_level[l] += other.hidden_by_level[l];
        }
        return *this;
    }
};

/// Called from one worker now and then: fraction of the work done (0..1) and the
/// seconds since the bake started.
using BakeProgress = std::function<void(double fraction, double elapsed_seconds)>;

/// Where a bake stands between top pairs. The bake resolves its top pairs in a fixed
/// order and a pair's bits do not depend on any other pair's, so a bake taken up from
/// a saved state gives the same table as one that never stopped.
struct BakeState {
    /// The first pairs_done top pairs, in the bake's order, are resolved; no later one
    /// has set a bit. [Limit: <= pairs_total]
    std::uint64_t pairs_done = 0;
    /// Top pairs in all (depends on the grid, the open and covered cells and top_level).
    std::uint64_t pairs_total = 0;
    /// The dense rows as those pairs left them: open_count() * words_per_row() words.
    std::span<const std::uint64_t> rows;
    /// The counts so far (`seconds`: the time of every run so far).
    CellBakeStats stats;
};

/// A bake that can stop and go on: every `interval_seconds` the workers pause between
/// top pairs and `save` gets the state (on the calling thread; the rows are valid
/// during the call only). With `resume`, the bake starts from that state, which must
/// come from a bake of the same scene, grid, settings and covered cells (the caller's
/// key says so): sizes that do not fit throw std::invalid_argument.
struct BakeCheckpoints {
    /// [Units: s] [Limit: > 0]
    double interval_seconds = 60.0;
    std::function<void(const BakeState&)> save;
    const BakeState* resume = nullptr;
    /// Asked every few milliseconds while the workers run (from a thread of the
    /// bake's; must be thread-safe): true brings the next save forward to now (a
    /// signal, say, after which `save` ends the bake by throwing).
    std::function<bool()> save_now;
};

/// A bake that gives up early when it would take too long. Once `sample_fraction` of
/// the top pairs it has left are resolved (at least 8 per worker; they come in a
/// scattered order, so they are a fair sample of the work), the bake predicts the time
/// of all the pairs it has left at their pace and throws BakeOverBudget when that is
/// over `max_seconds`; it gives up sooner when the sample alone has cost more than
/// sample_fraction of the budget. The time is CPU time over the workers (no more than
/// the cores): what the bake takes on an otherwise quiet machine, however busy this
/// one is, as long as nothing else in the process works. A bake that goes on from a
/// saved state is judged by the time it has left.
struct BakeBudget {
    /// Infinity: no budget. [Units: s of CPU per worker] [Limit: > 0]
    double max_seconds = std::numeric_limits<double>::infinity();
    /// [Limit: (0, 1]]
    double sample_fraction = 0.01;
    /// The CPU clock read (thread-safe, seconds); empty: the process's (std::clock).
    std::function<double()> cpu_seconds;

    [[nodiscard]] bool limited() const {
        return max_seconds < std::numeric_limits<double>::infinity();
    }
};

/// What a bake over its budget predicted when it gave up.
struct BakeOverBudget : std::runtime_error {
    BakeOverBudget(double predicted, double spent)
        : std::runtime_error("bake_cell_visibility: the bake would take longer than its budget"),
          predicted_seconds(predicted), spent_seconds(spent) {}
    /// The predicted time of the pairs the bake had left, as BakeBudget counts it.
    /// [Units: s]
    double predicted_seconds;
    /// What the sample took, as BakeBudget counts it. [Units: s]
    double spent_seconds;
};

/// The grid cells that are open: not inside the interior of one occluder (every corner
/// 1/64 unit inside all of its planes) and not empty space to `pruner` (may be null).
/// Increasing grid indexes.
[[nodiscard]] std::vector<std::uint32_t>
open_cells_of(const OccluderScene& scene, const CellGrid& grid, const BakePruner* pruner = nullptr);

/// Splits `open` (grid indexes) into the cells `covered` marks (one byte per grid
/// cell, nonzero: covered; empty: every cell) and the rest: {covered, uncovered}.
[[nodiscard]] std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>>
split_covered(std::vector<std::uint32_t> open, std::span<const std::uint8_t> covered);

/// Bakes the table over `grid` (validate(config) must be empty; the scene must have
/// its grid). `pruner` may be null. `covered` (one byte per grid cell, or empty: all)
/// says where the table must answer: open cells it does not mark become the table's
/// uncovered cells, which get no row and are never paired. Runs on config.threads
/// workers. With a limited `budget`, throws BakeOverBudget when the sample predicts
/// more (after `checkpoints.save` may have saved a state of it).
[[nodiscard]] CellVisibilityTable
bake_cell_visibility(const OccluderScene& scene, const CellGrid& grid, const CellBakeConfig& config,
                     const BakePruner* pruner = nullptr, CellBakeStats* stats = nullptr,
                     const BakeProgress& progress = {}, std::span<const std::uint8_t> covered = {},
                     const BakeCheckpoints& checkpoints = {}, const BakeBudget& budget = {});

} // namespace dsoc::visibility
