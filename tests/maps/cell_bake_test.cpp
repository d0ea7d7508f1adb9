// The baked cell visibility table against its slow, obviously correct twin: for
// pairs of cells the table calls hidden, segments between random open points of the
// two cells are cast against every occluder (brute force). Real maps with and without
// the compiler's PVS, with and without the bake's hierarchy. The tests also show that
// the table hides a large share of pairs, and that a wrong table is caught.

#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/player_space.hpp"
#include "dsoc/maps/pvs_bake_pruner.hpp"
#include "dsoc/visibility/cell_bake.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <random>

namespace dsoc::maps {
namespace {

using visibility::Aabb;
using visibility::CellVisibilityTable;
using visibility::OpenCell;

struct Loaded {
    Map map;
    std::shared_ptr<const visibility::OccluderScene> scene;
};

Loaded load(const std::string& spec) {
    auto map = load_map(spec, MapSearch::from_environment());
    if (!map) {
        throw std::runtime_error(map.error().message());
    }
    Loaded out{std::move(map).value(), nullptr};
    out.scene = visibility::OccluderScene::build(out.map.occluders);
    return out;
}

bool inside_some_occluder(const visibility::OccluderWorld& world, glm::vec3 p) {
    for (visibility::OccluderId id = 0; id < world.size(); ++id) {
        if (world.occluder(id).bounds().contains(p) && world.occluder(id).contains(p)) {
            return true;
        }
    }
    return false;
}

/// A random point of `box` where an eye or a visible point can be: outside every
/// occluder and, on a map with a PVS, in a leaf with a cluster (not in the compiler's
/// solid, not outside the map); nothing after 64 tries.
std::optional<glm::vec3> open_point(const visibility::OccluderWorld& world, const Pvs* pvs,
                                    const Aabb& box, std::mt19937& random) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<std::int32_t> clusters;
    for (int tries = 0; tries < 64; ++tries) {
        const glm::vec3 p =
            box.min + glm::vec3(unit(random), unit(random), unit(random)) * box.size();
        if (inside_some_occluder(world, p)) {
            continue;
        }
        if (pvs != nullptr && pvs->has_visibility() && !pvs->clusters_of(Aabb{p, p}, clusters)) {
            continue;
        }
        return p;
    }
    return std::nullopt;
}

struct Audit {
    std::size_t pairs_checked = 0;
    std::size_t segments = 0;
    /// Segments between "hidden" cells that no occluder blocks and that the compiler's
    /// PVS does not vouch for either: what the table must never have.
    std::size_t clear = 0;
    /// Segments no occluder blocks between points whose clusters the compiler's PVS
    /// calls apart: the PVS's own error, which the table inherits (as the culler's PVS
    /// stage and the Quake 3 server do). Counted, not failed.
    std::size_t pvs_apart = 0;
};

/// True when the PVS calls every cluster of `p` apart from every cluster of `q`.
bool pvs_apart(const Pvs& pvs, glm::vec3 p, glm::vec3 q) {
    std::vector<std::int32_t> a;
    std::vector<std::int32_t> b;
    if (!pvs.has_visibility() || !pvs.clusters_of(Aabb{p, p}, a) ||
        !pvs.clusters_of(Aabb{q, q}, b)) {
        return false;
    }
    for (const std::int32_t x : a) {
        for (const std::int32_t y : b) {
            if (pvs.cluster_visible(x, y) || pvs.cluster_visible(y, x)) {
                return false;
            }
        }
    }
    return true;
}

/// Casts `segments_per_pair` segments for up to `max_pairs` random hidden pairs.
Audit audit_hidden_pairs(const CellVisibilityTable& table, const visibility::OccluderWorld& world,
                         const Map* map, std::size_t max_pairs, int segments_per_pair,
                         unsigned seed) {
    const Pvs* pvs = map != nullptr ? map->pvs.get() : nullptr;
    const visibility::ReferenceVisibility reference(world);
    std::mt19937 random(seed);
    const auto n = static_cast<OpenCell>(table.open_count());
    std::uniform_int_distribution<OpenCell> pick(0, n - 1);
    Audit audit;
    for (std::size_t tries = 0; audit.pairs_checked < max_pairs && tries < max_pairs * 200;
         ++tries) {
        const OpenCell a = pick(random);
        const OpenCell b = pick(random);
        if (table.may_see(a, b)) {
            continue;
        }
        const auto& grid = table.grid();
        const Aabb box_a =
            grid.cell_box(grid.coords(table.open_cells()[static_cast<std::size_t>(a)]));
        const Aabb box_b =
            grid.cell_box(grid.coords(table.open_cells()[static_cast<std::size_t>(b)]));
        ++audit.pairs_checked;
        for (int k = 0; k < segments_per_pair; ++k) {
            const auto p = open_point(world, pvs, box_a, random);
            const auto q = open_point(world, pvs, box_b, random);
            if (!p || !q) {
                continue;
            }
            ++audit.segments;
            if (reference.segment_blocked(*p, *q)) {
                continue;
            }
            if (pvs != nullptr && pvs_apart(*pvs, *p, *q)) {
                ++audit.pvs_apart;
            } else {
                ++audit.clear;
            }
        }
    }
    return audit;
}

double hidden_fraction(const CellVisibilityTable& t) {
    const double n = static_cast<double>(t.open_count());
    return static_cast<double>(t.hidden_pairs()) / (n * n);
}

struct BakeCase {
    const char* map;
    float cell_size;
    int top_level;     ///< 0: no hierarchy
    double min_hidden; ///< the table must hide at least this share of cell pairs
    /// Rows only above walkable ground (a player space like the server's): the bake's
    /// blocks hold only covered cells.
    bool player_space = false;
};

class CellBakeProperty : public ::testing::TestWithParam<BakeCase> {};

TEST_P(CellBakeProperty, NoHiddenPairHasAClearSegment) {
    const BakeCase c = GetParam();
    if (std::string(c.map).rfind("gen:", 0) != 0) {
        DSOC_REQUIRE_OPENARENA();
    }
    const Loaded l = load(c.map);
    visibility::CellBakeConfig config;
    config.cell_size = c.cell_size;
    config.top_level = c.top_level;
    config.threads = 2;
    std::unique_ptr<PvsBakePruner> pruner;
    if (l.map.pvs != nullptr && l.map.pvs->has_visibility()) {
        pruner = std::make_unique<PvsBakePruner>(l.map.pvs);
    }
    const auto grid = visibility::CellGrid::covering(l.map.bounds, c.cell_size);
    visibility::CellBakeStats stats;
    std::vector<std::uint8_t> covered;
    if (c.player_space) {
        covered = cells_meeting(grid, player_space_boxes(l.map, PlayerSpace{0.7f, 160.0f, 64.0f}));
    }
    const auto table =
        visibility::bake_cell_visibility(*l.scene, grid, config, pruner.get(), &stats, {}, covered);
    ASSERT_GT(table.open_count(), 50u);
    if (c.player_space) {
        ASSERT_GT(table.uncovered_cells().size(), 0u);
    }
    // Symmetric, and every open cell sees itself.
    for (OpenCell a = 0; a < static_cast<OpenCell>(table.open_count()); a += 7) {
        EXPECT_TRUE(table.may_see(a, a));
        for (OpenCell b = 0; b < static_cast<OpenCell>(table.open_count()); b += 13) {
            ASSERT_EQ(table.may_see(a, b), table.may_see(b, a)) << a << " " << b;
        }
    }
    const Audit audit = audit_hidden_pairs(table, l.scene->world, &l.map, 1500, 4, 1234);
    EXPECT_GE(audit.segments, 3000u);
    EXPECT_EQ(audit.clear, 0u) << "segments between cells the table calls hidden that no "
                                  "occluder blocks and the PVS does not vouch for, of "
                               << audit.segments;
    EXPECT_GE(hidden_fraction(table), c.min_hidden);
    std::printf(
        "%s, %.0f-unit cells, top level %d: %zu open cells, %.1f%% of pairs hidden, "
        "%zu pairs / %zu segments audited, %zu clear (and %zu clear where the compiler's PVS "
        "calls the clusters apart); bake %.1f s, %llu exact tests\n",
        c.map, static_cast<double>(c.cell_size), c.top_level, table.open_count(),
        100.0 * hidden_fraction(table), audit.pairs_checked, audit.segments, audit.clear,
        audit.pvs_apart, stats.seconds, static_cast<unsigned long long>(stats.exact_tests));
}

INSTANTIATE_TEST_SUITE_P(RealMaps, CellBakeProperty,
                         ::testing::Values(BakeCase{"oa_dm4", 96.0f, 2, 0.5},
                                           BakeCase{"oa_dm4", 96.0f, 0, 0.5},
                                           BakeCase{"oa_dm4", 96.0f, 2, 0.5, true},
                                           BakeCase{"q3dm6ish", 128.0f, 2, 0.3},
                                           BakeCase{"oa_ctf2", 192.0f, 1, 0.02}),
                         [](const auto& param_info) {
                             std::string name = std::string(param_info.param.map) + "_top" +
                                                std::to_string(param_info.param.top_level) +
                                                (param_info.param.player_space ? "_space" : "");
                             for (char& ch : name) {
                                 ch = std::isalnum(static_cast<unsigned char>(ch)) != 0 ? ch : '_';
                             }
                             return name;
                         });

Loaded corridor() {
    Loaded out{test::corridor_map(), nullptr};
    out.scene = visibility::OccluderScene::build(out.map.occluders);
    return out;
}

TEST(CellBakeAudit, CatchesATableThatHidesTooMuch) {
    // The audit above has teeth: a table that calls every pair hidden is caught.
    const Loaded l = corridor();
    const auto grid = visibility::CellGrid::covering(l.map.bounds, 48.0f);
    const CellVisibilityTable all_hidden(grid, visibility::open_cells_of(*l.scene, grid));
    const Audit audit = audit_hidden_pairs(all_hidden, l.scene->world, nullptr, 500, 4, 99);
    EXPECT_GT(audit.clear, 100u);
}

TEST(CellBakeHierarchy, ProvesMostOfWhatSingleCellPairsProve) {
    // Block proofs hide every pair of their cells; refining where they fail must not
    // lose much against testing every pair of cells on its own.
    const Loaded l = corridor();
    const auto grid = visibility::CellGrid::covering(l.map.bounds, 48.0f);
    visibility::CellBakeConfig flat;
    flat.cell_size = 48.0f;
    flat.witness_stop_level = 0;
    flat.top_level = 0;
    flat.threads = 2;
    visibility::CellBakeConfig tree = flat;
    tree.top_level = 3;
    visibility::CellBakeStats flat_stats;
    visibility::CellBakeStats tree_stats;
    const auto a = visibility::bake_cell_visibility(*l.scene, grid, flat, nullptr, &flat_stats);
    const auto b = visibility::bake_cell_visibility(*l.scene, grid, tree, nullptr, &tree_stats);
    ASSERT_EQ(a.open_count(), b.open_count());
    EXPECT_GE(static_cast<double>(b.hidden_pairs()), 0.9 * static_cast<double>(a.hidden_pairs()));
    EXPECT_GT(b.hidden_pairs(), b.open_count() * b.open_count() / 4); // it culls
    // Both are sound: the flat table is the slow twin, audited like the other.
    EXPECT_EQ(audit_hidden_pairs(a, l.scene->world, nullptr, 800, 4, 5).clear, 0u);
    EXPECT_EQ(audit_hidden_pairs(b, l.scene->world, nullptr, 800, 4, 6).clear, 0u);
    std::printf("corridor, 48-unit cells: flat %llu hidden pairs in %llu visits, hierarchy %llu "
                "in %llu\n",
                static_cast<unsigned long long>(a.hidden_pairs()),
                static_cast<unsigned long long>(flat_stats.pair_visits),
                static_cast<unsigned long long>(b.hidden_pairs()),
                static_cast<unsigned long long>(tree_stats.pair_visits));
    EXPECT_LT(tree_stats.pair_visits, flat_stats.pair_visits);
}

} // namespace
} // namespace dsoc::maps
