// A bake with a time budget: a budget it keeps changes nothing; one it would overrun
// is given up on a sample of its pairs, before the whole bake; a bake that goes on from
// a saved state samples the pairs left; the cache then grows the cells step
// by step, leaves no partial file of a grid it gave up on, and bakes the last grid
// whatever it takes.

#include "dsoc/maps/bake_cache.hpp"
#include "support/temp_dir.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dsoc::maps {
namespace {

namespace fs = std::filesystem;

const Map& corridor() {
    return test::shared_corridor().map;
}
const visibility::OccluderScene& corridor_scene() {
    return *test::shared_corridor().scene;
}

visibility::CellBakeConfig config() {
    visibility::CellBakeConfig c;
    c.cell_size = 128.0f; // coarse: a few hundred top pairs
    c.threads = 2;
    c.top_level = 1;
    return c;
}

/// A budget no bake keeps: any CPU time at all is over it.
visibility::BakeBudget impossible_budget(double sample_fraction) {
    visibility::BakeBudget b;
    b.max_seconds = 1e-12;
    b.sample_fraction = sample_fraction;
    return b;
}

TEST(BakeBudget, AKeptBudgetChangesNothingAndAnOverrunOneIsGivenUpOnASample) {
    const auto grid =
        bake_grid(corridor(), corridor_scene(), 128.0f, std::uint64_t{128} << 20, std::nullopt);
    const auto whole = visibility::bake_cell_visibility(corridor_scene(), grid, config());
    ASSERT_GT(whole.hidden_pairs(), 0u); // the table does hide something

    visibility::BakeBudget generous;
    generous.max_seconds = 1e6;
    generous.sample_fraction = 0.5;
    visibility::CellBakeStats stats;
    EXPECT_TRUE(visibility::bake_cell_visibility(corridor_scene(), grid, config(), nullptr, &stats,
                                                 {}, {}, {}, generous) == whole);
    EXPECT_GT(stats.predicted_seconds, 0.0); // the sample's prediction is reported

    // Half the pairs as the sample: enough CPU time to measure, and the bake gives up
    // with a prediction of more than the sample took.
    double last_fraction = 0.0;
    try {
        (void)visibility::bake_cell_visibility(
            corridor_scene(), grid, config(), nullptr, nullptr,
            [&](double fraction, double) { last_fraction = fraction; }, {}, {},
            impossible_budget(0.5));
        ADD_FAILURE() << "a bake over its budget finished";
    } catch (const visibility::BakeOverBudget& over) {
        EXPECT_GT(over.spent_seconds, 0.0);
        EXPECT_GT(over.predicted_seconds, over.spent_seconds);
        EXPECT_LT(last_fraction, 1.0); // it never reported the whole bake done
    }

    EXPECT_THROW((void)visibility::bake_cell_visibility(corridor_scene(), grid, config(), nullptr,
                                                        nullptr, {}, {}, {},
                                                        impossible_budget(0.0)),
                 std::invalid_argument);
}

TEST(BakeBudget, ABakeThatGoesOnFromASavedStateIsJudgedByThePaceOfThePairsLeft) {
    const auto grid =
        bake_grid(corridor(), corridor_scene(), 128.0f, std::uint64_t{128} << 20, std::nullopt);
    const auto whole = visibility::bake_cell_visibility(corridor_scene(), grid, config());
    std::vector<std::uint64_t> rows;
    visibility::BakeState saved;
    visibility::BakeCheckpoints save_once;
    save_once.interval_seconds = 1e-6;
    save_once.save = [&](const visibility::BakeState& s) {
        if (rows.empty()) {
            rows.assign(s.rows.begin(), s.rows.end());
            saved = s;
            saved.rows = rows;
        }
    };
    (void)visibility::bake_cell_visibility(corridor_scene(), grid, config(), nullptr, nullptr, {},
                                           {}, save_once);
    ASSERT_FALSE(rows.empty());
    ASSERT_LT(saved.pairs_done, saved.pairs_total);
    visibility::BakeCheckpoints resume;
    resume.resume = &saved;
    EXPECT_THROW((void)visibility::bake_cell_visibility(corridor_scene(), grid, config(), nullptr,
                                                        nullptr, {}, {}, resume,
                                                        impossible_budget(0.5)),
                 visibility::BakeOverBudget);
    visibility::BakeBudget generous;
    generous.max_seconds = 1e6;
    generous.sample_fraction = 0.5;
    EXPECT_TRUE(visibility::bake_cell_visibility(corridor_scene(), grid, config(), nullptr, nullptr,
                                                 {}, {}, resume, generous) == whole);
}

TEST(BakeBudgetCache, CellsGrowPastEveryGridOverTheBudgetAndTheLastIsBakedAnyway) {
    const testing::TempDir temp("dsoc-budget-test-" +
                                std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    const fs::path& dir = temp.dir();
    BakeRequest r;
    r.config = config();
    r.dir = dir;
    r.checkpoint_seconds = 1e-6; // a partial file of every grid tried, were any kept
    r.max_bake_seconds = 1e-12;
    r.budget_sample_fraction = 0.5; // saves come before the bake gives up
    const auto baked = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_TRUE(baked.ok()) << baked.error().message();
    EXPECT_FALSE(baked->from_cache);
    ASSERT_GE(baked->over_budget.size(), 2u);
    EXPECT_EQ(baked->over_budget.front().cell_size, 128.0f); // the memory budget's grid first
    for (std::size_t i = 1; i < baked->over_budget.size(); ++i) {
        EXPECT_GT(baked->over_budget[i].cell_size, baked->over_budget[i - 1].cell_size);
    }
    for (const GridOverBudget& over : baked->over_budget) {
        EXPECT_LE(over.cell_size, 1024.0f);
        EXPECT_EQ(over.budget_seconds, 1e-12);
        EXPECT_NE(describe(over).find("over the 0 s budget"), std::string::npos) << describe(over);
    }
    EXPECT_GT(baked->table->grid().cell_size, 1024.0f); // the last grid, baked whatever it takes
    EXPECT_TRUE(fs::exists(baked->file));
    for (const auto& entry : fs::directory_iterator(dir)) {
        EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
    }

    // With the default budget the table baked is taken from the cache, not baked again.
    r.max_bake_seconds = BakeRequest{}.max_bake_seconds;
    const auto again = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_TRUE(again.ok());
    EXPECT_TRUE(again->from_cache);
    EXPECT_EQ(again->file, baked->file);

    r.max_bake_seconds = 0.0;
    EXPECT_FALSE(load_or_bake(corridor(), corridor_scene(), r).ok());
}

} // namespace
} // namespace dsoc::maps
