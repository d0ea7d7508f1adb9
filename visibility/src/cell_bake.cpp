#include "dsoc/visibility/cell_bake.hpp"

#include "bake_budget_judge.hpp"

#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"
#include "dsoc/visibility/shuffled_pairs.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>

namespace dsoc::visibility {

namespace {

/// Points outside every occluder kept per open cell for witness segments.
constexpr int kSamplesPerCell = 8;

/// One level of the block hierarchy: level l holds blocks of 2^l cells per side.
/// Per block: its open cells, the box of those cells, a representative point (the
/// centre of its open cell nearest the block's centre) and the pruner's keys.
struct Level {
    glm::ivec3 dims{0};
    std::vector<std::uint32_t> open_start; ///< CSR into `open`, one more than blocks
    std::vector<OpenCell> open;
    std::vector<Aabb> box;
    std::vector<glm::vec3> rep;
    std::vector<std::uint32_t> key_start;
    std::vector<std::int32_t> keys;

    [[nodiscard]] std::size_t size() const { return box.size(); }
    [[nodiscard]] std::uint32_t index(glm::ivec3 b) const {
        return static_cast<std::uint32_t>((b.z * dims.y + b.y) * dims.x + b.x);
    }
    [[nodiscard]] std::span<const OpenCell> cells(std::uint32_t i) const {
        return {open.data() + open_start[i], open_start[i + 1] - open_start[i]};
    }
    [[nodiscard]] std::span<const std::int32_t> keys_of(std::uint32_t i) const {
        return {keys.data() + key_start[i], key_start[i + 1] - key_start[i]};
    }
    [[nodiscard]] bool empty(std::uint32_t i) const { return open_start[i] == open_start[i + 1]; }
};

struct Node {
    int level;
    std::uint32_t index;
};

class Baker {
public:
    Baker(const OccluderScene& scene, const CellGrid& grid, const CellBakeConfig& config,
          const BakePruner* pruner, CellVisibilityTable& table)
        : scene_(scene), grid_(grid), config_(config), pruner_(pruner), table_(table) {
        build_levels();
        build_samples();
    }

    /// Resolves the top pairs from checkpoints.resume's (or from the first), saving
    /// the state every checkpoints.interval_seconds; adds to `stats` the work counts
    /// of this run and of the resumed ones, and sets its seconds to all of theirs.
    void run(CellBakeStats& stats, const BakeProgress& progress, const BakeCheckpoints& checkpoints,
             const BakeBudget& budget);

private:
    struct Worker {
        ShaftOcclusion::Scratch shaft;
        OccluderGrid::Scratch segment;
        CellBakeStats stats;
    };

    void build_levels();
    /// Up to kSamplesPerCell points of each open cell outside every occluder.
    void build_samples();
    /// A deterministic stream of random numbers for one pair of blocks, so that the
    /// table does not depend on which worker resolved which pair (splitmix64).
    struct PairRandom {
        std::uint64_t state;
        std::uint64_t next() {
            std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
            return z ^ (z >> 31);
        }
    };
    [[nodiscard]] glm::vec3 random_sample(PairRandom& random, Node n) const;
    void resolve_self(Worker& w, Node a);
    void resolve(Worker& w, Node a, Node b);
    void mark_all(Node a, Node b);
    [[nodiscard]] bool segment_clear(Worker& w, glm::vec3 p, glm::vec3 q) const;
    /// True when one of config_.witness_segments segments between the blocks is clear.
    [[nodiscard]] bool witness(Worker& w, Node a, Node b) const;
    [[nodiscard]] bool exact_hidden(Worker& w, const Aabb& region, const Aabb& box,
                                    int level) const;
    template <typename F>
    void for_children(Node n, F&& f) const;

    const OccluderScene& scene_;
    const CellGrid& grid_;
    const CellBakeConfig& config_;
    const BakePruner* pruner_;
    CellVisibilityTable& table_;
    std::vector<Level> levels_;
    std::vector<std::uint32_t> sample_start_; ///< CSR by open cell into samples_
    std::vector<glm::vec3> samples_;
};

void Baker::build_samples() {
    const OccluderWorld& world = scene_.world;
    std::mt19937 random(0x5a3b1e5u);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const auto open = [&](glm::vec3 p) {
        for (const OccluderId id : scene_.grid->items_at(p)) {
            if (world.occluder(id).bounds().contains(p) && world.occluder(id).contains(p)) {
                return false;
            }
        }
        return true;
    };
    sample_start_.assign(1, 0);
    for (const std::uint32_t cell : table_.open_cells()) {
        const Aabb box = grid_.cell_box(grid_.coords(cell));
        int kept = 0;
        if (open(box.center())) {
            samples_.push_back(box.center());
            ++kept;
        }
        for (int tries = 0; tries < 4 * kSamplesPerCell && kept < kSamplesPerCell; ++tries) {
            const glm::vec3 p =
                box.min + glm::vec3(unit(random), unit(random), unit(random)) * box.size();
            if (open(p)) {
                samples_.push_back(p);
                ++kept;
            }
        }
        if (kept == 0) {
            samples_.push_back(box.center()); // all solid as far as we looked
        }
        sample_start_.push_back(static_cast<std::uint32_t>(samples_.size()));
    }
}

glm::vec3 Baker::random_sample(PairRandom& random, Node n) const {
    const auto cells = levels_[static_cast<std::size_t>(n.level)].cells(n.index);
    const auto c = static_cast<std::size_t>(cells[random.next() % cells.size()]);
    const std::uint32_t first = sample_start_[c];
    const std::uint32_t count = sample_start_[c + 1] - first;
    return samples_[first + static_cast<std::uint32_t>(random.next() % count)];
}

void Baker::build_levels() {
    const int top = config_.top_level;
    levels_.resize(static_cast<std::size_t>(top) + 1);
    std::vector<glm::vec3> centre(table_.open_count());
    {
        Level& l0 = levels_[0];
        l0.dims = grid_.dims;
        const std::size_t n = grid_.cell_count();
        l0.open_start.reserve(n + 1);
        l0.open_start.push_back(0);
        l0.box.resize(n);
        l0.rep.resize(n);
        for (std::uint32_t i = 0; i < n; ++i) {
            const Aabb box = grid_.cell_box(grid_.coords(i));
            const OpenCell c = table_.open_index(i);
            if (c >= 0) {
                l0.open.push_back(c);
                l0.box[i] = box;
                l0.rep[i] = box.center();
                centre[static_cast<std::size_t>(c)] = box.center();
            }
            l0.open_start.push_back(static_cast<std::uint32_t>(l0.open.size()));
        }
    }
    for (int l = 1; l <= top; ++l) {
        const Level& below = levels_[static_cast<std::size_t>(l) - 1];
        Level& level = levels_[static_cast<std::size_t>(l)];
        level.dims = (below.dims + 1) / 2;
        const std::size_t n = static_cast<std::size_t>(level.dims.x) * level.dims.y * level.dims.z;
        level.open_start.reserve(n + 1);
        level.open_start.push_back(0);
        level.box.resize(n);
        level.rep.resize(n);
        for (std::uint32_t i = 0; i < n; ++i) {
            const int x = static_cast<int>(i % static_cast<std::uint32_t>(level.dims.x));
            const int y = static_cast<int>(i / static_cast<std::uint32_t>(level.dims.x) %
                                           static_cast<std::uint32_t>(level.dims.y));
            const int z = static_cast<int>(i / static_cast<std::uint32_t>(level.dims.x) /
                                           static_cast<std::uint32_t>(level.dims.y));
            Aabb box;
            for (int k = 0; k < 8; ++k) {
                const glm::ivec3 c{2 * x + (k & 1), 2 * y + (k >> 1 & 1), 2 * z + (k >> 2 & 1)};
                if (c.x >= below.dims.x || c.y >= below.dims.y || c.z >= below.dims.z) {
                    continue;
                }
                const std::uint32_t child = below.index(c);
                if (below.empty(child)) {
                    continue;
                }
                const auto cells = below.cells(child);
                level.open.insert(level.open.end(), cells.begin(), cells.end());
                box.extend(below.box[child]);
            }
            level.open_start.push_back(static_cast<std::uint32_t>(level.open.size()));
            level.box[i] = box;
            if (!box.is_empty()) {
                const glm::vec3 mid = box.center();
                float best = std::numeric_limits<float>::max();
                for (const OpenCell c : level.cells(i)) {
                    const glm::vec3 d = centre[static_cast<std::size_t>(c)] - mid;
                    const float d2 = glm::dot(d, d);
                    if (d2 < best) {
                        best = d2;
                        level.rep[i] = centre[static_cast<std::size_t>(c)];
                    }
                }
            }
        }
    }
    std::vector<std::int32_t> keys;
    for (Level& level : levels_) {
        level.key_start.assign(1, 0);
        for (std::uint32_t i = 0; i < level.size(); ++i) {
            if (pruner_ != nullptr && !level.empty(i)) {
                pruner_->keys(level.box[i], keys);
                level.keys.insert(level.keys.end(), keys.begin(), keys.end());
            }
            level.key_start.push_back(static_cast<std::uint32_t>(level.keys.size()));
        }
    }
}

template <typename F>
void Baker::for_children(Node n, F&& f) const {
    const Level& level = levels_[static_cast<std::size_t>(n.level)];
    const Level& below = levels_[static_cast<std::size_t>(n.level) - 1];
    const int x = static_cast<int>(n.index % static_cast<std::uint32_t>(level.dims.x));
    const int y = static_cast<int>(n.index / static_cast<std::uint32_t>(level.dims.x) %
                                   static_cast<std::uint32_t>(level.dims.y));
    const int z = static_cast<int>(n.index / static_cast<std::uint32_t>(level.dims.x) /
                                   static_cast<std::uint32_t>(level.dims.y));
    for (int k = 0; k < 8; ++k) {
        const glm::ivec3 c{2 * x + (k & 1), 2 * y + (k >> 1 & 1), 2 * z + (k >> 2 & 1)};
        if (c.x < below.dims.x && c.y < below.dims.y && c.z < below.dims.z) {
            const std::uint32_t child = below.index(c);
            if (!below.empty(child)) {
                f(Node{n.level - 1, child});
            }
        }
    }
}

bool Baker::segment_clear(Worker& w, glm::vec3 p, glm::vec3 q) const {
    const OccluderWorld& world = scene_.world;
    const SegmentRay ray = SegmentRay::between(p, q);
    // The first blocker ends the walk: most segments between hidden pairs meet one
    // long before their end.
    return !scene_.grid->any_along_segment(p, q, w.segment, [&](OccluderId id) {
        const Aabb& solid = world.solid_box(id);
        if (!solid.is_empty()) {
            return segment_through_box(ray, solid);
        }
        // A convex solid lies within its bounds: a segment that misses them (grown by
        // kBoxShrink against rounding) misses its interior, for a slab test instead
        // of a clip against every plane. (Were it wrong, a blocked segment would be
        // called clear: a pair marked visible, never one hidden.)
        const Aabb& bounds = world.occluder(id).bounds();
        float t0 = 0.0f;
        float t1 = 1.0f;
        return clip_segment_to_box(
                   p, ray.inv,
                   Aabb{bounds.min - glm::vec3(kBoxShrink), bounds.max + glm::vec3(kBoxShrink)}, t0,
                   t1) &&
               segment_blocked_by(p, q, world.solid_planes(id));
    });
}

bool Baker::witness(Worker& w, Node a, Node b) const {
    const Level& la = levels_[static_cast<std::size_t>(a.level)];
    const Level& lb = levels_[static_cast<std::size_t>(b.level)];
    ++w.stats.witness_rays;
    if (segment_clear(w, la.rep[a.index], lb.rep[b.index])) {
        return true;
    }
    PairRandom random{(static_cast<std::uint64_t>(a.level) << 60) ^
                      (static_cast<std::uint64_t>(a.index) << 32) ^
                      (static_cast<std::uint64_t>(b.level) << 28) ^ b.index};
    for (int k = 1; k < config_.witness_segments; ++k) {
        ++w.stats.witness_rays;
        if (segment_clear(w, random_sample(random, a), random_sample(random, b))) {
            return true;
        }
    }
    return false;
}

bool Baker::exact_hidden(Worker& w, const Aabb& region, const Aabb& box, int level) const {
    ++w.stats.exact_tests;
    ++w.stats.exact_by_level[level];
    const ShaftOcclusion shaft(scene_.world, *scene_.grid, true, config_.portal_depth);
    const bool hidden = shaft.test(region, box, w.shaft) == Visibility::occluded;
    w.stats.exact_hidden += hidden ? 1 : 0;
    w.stats.hidden_by_level[level] += hidden ? 1 : 0;
    return hidden;
}

void Baker::mark_all(Node a, Node b) {
    const auto ca = levels_[static_cast<std::size_t>(a.level)].cells(a.index);
    const auto cb = levels_[static_cast<std::size_t>(b.level)].cells(b.index);
    for (const OpenCell x : ca) {
        for (const OpenCell y : cb) {
            table_.set_visible_atomic(x, y);
        }
    }
}

void Baker::resolve_self(Worker& w, Node a) {
    if (a.level == 0) {
        const OpenCell c = levels_[0].cells(a.index)[0];
        table_.set_visible_atomic(c, c);
        return;
    }
    Node children[8];
    int n = 0;
    for_children(a, [&](Node c) { children[n++] = c; });
    for (int i = 0; i < n; ++i) {
        resolve_self(w, children[i]);
        for (int j = i + 1; j < n; ++j) {
            resolve(w, children[i], children[j]);
        }
    }
}

void Baker::resolve(Worker& w, Node a, Node b) {
    ++w.stats.pair_visits;
    const Level& la = levels_[static_cast<std::size_t>(a.level)];
    const Level& lb = levels_[static_cast<std::size_t>(b.level)];
    if (pruner_ != nullptr && pruner_->hidden(la.keys_of(a.index), lb.keys_of(b.index))) {
        ++w.stats.pruned;
        return;
    }
    const bool clear = witness(w, a, b);
    const bool leaves = a.level == 0 && b.level == 0;
    if (clear) {
        ++w.stats.witness_clear;
        if (a.level <= config_.witness_stop_level && b.level <= config_.witness_stop_level) {
            mark_all(a, b);
            return;
        }
    } else {
        const int level = std::max(a.level, b.level);
        if (exact_hidden(w, la.box[a.index], lb.box[b.index], level)) {
            return;
        }
        if (leaves) {
            if (config_.both_directions && exact_hidden(w, lb.box[b.index], la.box[a.index], 0)) {
                return;
            }
            mark_all(a, b);
            return;
        }
    }
    // Refine the larger block (both are never leaves here).
    if (a.level >= b.level) {
        for_children(a, [&](Node c) { resolve(w, c, b); });
    } else {
        for_children(b, [&](Node c) { resolve(w, a, c); });
    }
}

void Baker::run(CellBakeStats& stats, const BakeProgress& progress,
                const BakeCheckpoints& checkpoints, const BakeBudget& budget) {
    const auto start = std::chrono::steady_clock::now();
    const int top = config_.top_level;
    const Level& level = levels_[static_cast<std::size_t>(top)];
    std::vector<std::uint32_t> blocks;
    for (std::uint32_t i = 0; i < level.size(); ++i) {
        if (!level.empty(i)) {
            blocks.push_back(i);
        }
    }
    // Every unordered pair of top blocks, a block with itself included, in a scattered
    // order (ShuffledPairs: no list of n² pairs is held).
    const ShuffledPairs work(blocks.size());
    CellBakeStats before; // of the runs a resumed state stands for
    std::uint64_t first = 0;
    if (const BakeState* resume = checkpoints.resume; resume != nullptr) {
        if (resume->pairs_total != work.count() || resume->pairs_done > work.count() ||
            resume->rows.size() != table_.words().size()) {
            throw std::invalid_argument("bake_cell_visibility: the state to resume is of "
                                        "another bake (its pairs or rows do not fit)");
        }
        // No bit past the last open cell in any row (the table's own invariant).
        const std::size_t per_row = table_.words_per_row();
        const std::size_t tail = table_.open_count() % 64;
        for (std::size_t r = 0; tail != 0 && r < table_.open_count(); ++r) {
            if ((resume->rows[r * per_row + per_row - 1] >> tail) != 0) {
                throw std::invalid_argument("bake_cell_visibility: the state to resume has "
                                            "bits past the last open cell");
            }
        }
        std::copy(resume->rows.begin(), resume->rows.end(), table_.words().begin());
        first = resume->pairs_done;
        before = resume->stats;
    }

    unsigned threads = config_.threads > 0 ? static_cast<unsigned>(config_.threads)
                                           : std::max(1u, std::thread::hardware_concurrency());
    threads = static_cast<unsigned>(
        std::min<std::uint64_t>(threads, std::max<std::uint64_t>(1, work.count())));
    std::atomic<std::uint64_t> next{first};
    std::atomic<std::uint64_t> done{first};
    // Set when a save is due: each worker stops before taking another pair, so that
    // the pairs resolved are exactly those below `next`.
    std::atomic<bool> pause{false};
    std::vector<Worker> workers(threads);
    BakeBudgetJudge judge(budget, first, work.count(), threads);
    const auto body = [&](unsigned t) {
        Worker& w = workers[t];
        auto last_report = std::chrono::steady_clock::now();
        // At least one pair a round, so that rounds always move on however short the
        // interval between saves.
        for (bool first_pair = true; first_pair || !pause.load(std::memory_order_relaxed);
             first_pair = false) {
            const std::uint64_t k = next.fetch_add(1);
            if (k >= work.count()) {
                break;
            }
            const auto [a, b] = work.at(k);
            const std::uint32_t i = blocks[a];
            const std::uint32_t j = blocks[b];
            if (i == j) {
                resolve_self(w, Node{top, i});
            } else {
                resolve(w, Node{top, i}, Node{top, j});
            }
            const std::uint64_t finished = done.fetch_add(1) + 1;
            if (judge.over_budget_after(finished)) {
                pause.store(true);
            }
            if (t == 0 && progress) {
                const auto now = std::chrono::steady_clock::now();
                if (now - last_report > std::chrono::milliseconds(500)) {
                    last_report = now;
                    progress(static_cast<double>(finished) / static_cast<double>(work.count()),
                             before.seconds + std::chrono::duration<double>(now - start).count());
                }
            }
        }
    };
    const auto counts = [&] {
        CellBakeStats sum = before;
        for (const Worker& w : workers) {
            sum.add_work(w.stats);
        }
        sum.seconds =
            before.seconds +
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return sum;
    };
    const auto interval = std::chrono::duration<double>(
        checkpoints.save ? checkpoints.interval_seconds : std::numeric_limits<double>::infinity());
    while (true) {
        // A round: every worker (this thread is worker 0) takes pairs until they run
        // out or a save is due, then the state is saved and the next round begins.
        pause.store(false);
        std::vector<std::thread> pool;
        for (unsigned t = 1; t < threads; ++t) {
            pool.emplace_back(body, t);
        }
        const auto since = std::chrono::steady_clock::now();
        std::thread timer;
        std::atomic<bool> stop_timer{false};
        if (checkpoints.save) {
            timer = std::thread([&] {
                while (!stop_timer.load() && !pause.load()) {
                    if (std::chrono::steady_clock::now() - since >= interval ||
                        (checkpoints.save_now && checkpoints.save_now())) {
                        pause.store(true);
                        break;
                    }
                    std::this_thread::sleep_for(std::chrono::milliseconds(20));
                }
            });
        }
        body(0);
        for (auto& th : pool) {
            th.join();
        }
        stop_timer.store(true);
        if (timer.joinable()) {
            timer.join();
        }
        // Every pair handed out was resolved: the first min(next, count) are done.
        const std::uint64_t resolved = std::min<std::uint64_t>(next.load(), work.count());
        next.store(resolved);
        if (resolved == work.count()) {
            break; // done, whatever the budget said
        }
        if (judge.over_budget()) {
            throw BakeOverBudget(judge.predicted_seconds(), judge.sample_seconds());
        }
        checkpoints.save(BakeState{resolved, work.count(), table_.words(), counts()});
    }
    const CellBakeStats all = counts();
    stats.add_work(all);
    stats.seconds = all.seconds;
    stats.predicted_seconds = judge.predicted_seconds();
    if (progress) {
        progress(1.0, stats.seconds);
    }
}

} // namespace

std::vector<std::string> validate(const CellBakeConfig& c) {
    std::vector<std::string> problems;
    if (!(c.cell_size >= 4.0f && c.cell_size <= 1024.0f)) {
        problems.push_back("cell_size must be within 4..1024 world units");
    }
    if (c.threads < 0 || c.threads > 256) {
        problems.push_back("threads must be within 0..256");
    }
    if (c.portal_depth < 0 || c.portal_depth > 4) {
        problems.push_back("portal_depth must be within 0..4");
    }
    if (c.top_level < 0 || c.top_level > 6) {
        problems.push_back("top_level must be within 0..6");
    }
    if (c.witness_segments < 1 || c.witness_segments > 64) {
        problems.push_back("witness_segments must be within 1..64");
    }
    if (c.witness_stop_level < 0 || c.witness_stop_level > 3) {
        problems.push_back("witness_stop_level must be within 0..3");
    }
    return problems;
}

CellVisibilityTable bake_cell_visibility(const OccluderScene& scene, const CellGrid& grid,
                                         const CellBakeConfig& config, const BakePruner* pruner,
                                         CellBakeStats* stats, const BakeProgress& progress,
                                         std::span<const std::uint8_t> covered,
                                         const BakeCheckpoints& checkpoints,
                                         const BakeBudget& budget) {
    if (const auto problems = validate(config); !problems.empty()) {
        throw std::invalid_argument("CellBakeConfig: " + problems.front());
    }
    if (scene.grid == nullptr) {
        throw std::invalid_argument("bake_cell_visibility: the scene has no occluder grid");
    }
    if (!(budget.max_seconds > 0.0) ||
        !(budget.sample_fraction > 0.0 && budget.sample_fraction <= 1.0)) {
        throw std::invalid_argument("bake_cell_visibility: a budget needs max_seconds > 0 and "
                                    "sample_fraction within (0, 1]");
    }
    auto [open, uncovered] = split_covered(open_cells_of(scene, grid, pruner), covered);
    CellVisibilityTable table(grid, std::move(open), std::move(uncovered));
    CellBakeStats local;
    local.cells = grid.cell_count();
    local.open_cells = table.open_count();
    local.uncovered_cells = table.uncovered_cells().size();
    if (table.open_count() > 0) {
        Baker baker(scene, grid, config, pruner, table);
        baker.run(local, progress, checkpoints, budget);
    }
    table.compress();
    if (stats != nullptr) {
        *stats = local;
    }
    return table;
}

} // namespace dsoc::visibility
