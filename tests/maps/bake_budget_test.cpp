// A bake with a time budget: the time of the pairs left is predicted from a sample at
// their pace (a bake that goes on from a saved state by the pairs it has left); a
// budget kept changes nothing; one overrun is given up at the end of the sample, or
// sooner when the sample alone costs more than its share; the cache then grows the
// cells step by step, says so at once, and removes the partial file of a grid it gave
// up on (but keeps one it went on from).
//
// Most checks read a fake CPU clock that advances 1 ms at every read: on one thread the
// bake reads it once at the start and once after every pair until it decides, so d
// pairs cost d ms and every prediction is exactly 1 ms a pair.

#include "dsoc/maps/bake_cache.hpp"
#include "support/temp_dir.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <atomic>
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

constexpr double kMsPerPair = 1e-3;

visibility::CellBakeConfig config(int threads = 1) {
    visibility::CellBakeConfig c;
    c.cell_size = 128.0f; // coarse: a few hundred top pairs
    c.threads = threads;
    c.top_level = 1;
    return c;
}

const visibility::CellGrid& grid() {
    static const auto g =
        bake_grid(corridor(), corridor_scene(), 128.0f, std::uint64_t{128} << 20, std::nullopt);
    return g;
}

/// A clock of 1 ms a read (thread-safe).
struct FakeClock {
    std::shared_ptr<std::atomic<std::uint64_t>> reads =
        std::make_shared<std::atomic<std::uint64_t>>(0);
    [[nodiscard]] std::function<double()> function() const {
        auto r = reads;
        return [r] { return static_cast<double>(++*r) * kMsPerPair; };
    }
};

visibility::BakeBudget budget(double max_seconds, double sample_fraction = 0.5) {
    visibility::BakeBudget b;
    b.max_seconds = max_seconds;
    b.sample_fraction = sample_fraction;
    b.cpu_seconds = FakeClock{}.function();
    return b;
}

/// The bake's top pairs (from a state it saves).
std::uint64_t pair_count() {
    static const std::uint64_t count = [] {
        std::uint64_t total = 0;
        visibility::BakeCheckpoints once;
        once.interval_seconds = 1e-6;
        once.save = [&](const visibility::BakeState& s) { total = s.pairs_total; };
        (void)visibility::bake_cell_visibility(corridor_scene(), grid(), config(), nullptr, nullptr,
                                               {}, {}, once);
        return total;
    }();
    return count;
}

TEST(BakeBudget, AKeptBudgetChangesNothingAndPredictsThePairsAtTheirPace) {
    const auto whole = visibility::bake_cell_visibility(corridor_scene(), grid(), config());
    ASSERT_GT(whole.hidden_pairs(), 0u); // the table does hide something
    const auto n = static_cast<double>(pair_count());
    ASSERT_GE(n, 100.0);
    visibility::CellBakeStats stats;
    EXPECT_TRUE(visibility::bake_cell_visibility(corridor_scene(), grid(), config(), nullptr,
                                                 &stats, {}, {}, {},
                                                 budget(1.05 * kMsPerPair * n)) == whole);
    EXPECT_NEAR(stats.predicted_seconds, kMsPerPair * n, 1e-9);
    // On the real clock too (two workers): the same table, some prediction.
    visibility::BakeBudget real;
    real.max_seconds = 1e6;
    EXPECT_TRUE(visibility::bake_cell_visibility(corridor_scene(), grid(), config(2), nullptr,
                                                 &stats, {}, {}, {}, real) == whole);
    EXPECT_GT(stats.predicted_seconds, 0.0);
}

TEST(BakeBudget, AnOverrunIsGivenUpAtTheSampleOrSoonerWhenTheSampleAloneCostsTooMuch) {
    const auto n = static_cast<double>(pair_count());
    const auto over = [&](double max_seconds) -> visibility::BakeOverBudget {
        double last_fraction = 0.0;
        try {
            (void)visibility::bake_cell_visibility(
                corridor_scene(), grid(), config(), nullptr, nullptr,
                [&](double fraction, double) { last_fraction = fraction; }, {}, {},
                budget(max_seconds));
        } catch (const visibility::BakeOverBudget& e) {
            EXPECT_LT(last_fraction, 1.0); // never reported the whole bake done
            return e;
        }
        ADD_FAILURE() << "a bake over its budget of " << max_seconds << " s finished";
        return {0.0, 0.0};
    };
    // Just over: decided when half the pairs (the sample) are done, or a pair or two
    // before, when the sample passes half the budget.
    const auto near = over(0.95 * kMsPerPair * n);
    EXPECT_NEAR(near.predicted_seconds, kMsPerPair * n, 1e-9);
    EXPECT_GE(near.spent_seconds, 0.47 * kMsPerPair * n);
    EXPECT_LE(near.spent_seconds, 0.5 * kMsPerPair * n + 2 * kMsPerPair);
    // Far over: given up once the sample has cost half the budget, long before its end.
    const double small = 10.0 * kMsPerPair;
    const auto far = over(small);
    EXPECT_NEAR(far.predicted_seconds, kMsPerPair * n, 1e-9);
    EXPECT_LE(far.spent_seconds, 0.5 * small + kMsPerPair);

    visibility::BakeBudget bad;
    bad.max_seconds = 1.0;
    bad.sample_fraction = 0.0;
    EXPECT_THROW((void)visibility::bake_cell_visibility(corridor_scene(), grid(), config(), nullptr,
                                                        nullptr, {}, {}, {}, bad),
                 std::invalid_argument);
}

TEST(BakeBudget, ABakeThatGoesOnFromASavedStateIsJudgedByThePairsItHasLeft) {
    const auto whole = visibility::bake_cell_visibility(corridor_scene(), grid(), config());
    std::vector<std::uint64_t> rows;
    visibility::BakeState saved;
    visibility::BakeCheckpoints save;
    save.interval_seconds = 1e-6;
    save.save = [&](const visibility::BakeState& s) {
        if (s.pairs_done * 3 >= s.pairs_total && rows.empty()) { // a third done
            rows.assign(s.rows.begin(), s.rows.end());
            saved = s;
            saved.rows = rows;
        }
    };
    (void)visibility::bake_cell_visibility(corridor_scene(), grid(), config(), nullptr, nullptr, {},
                                           {}, save);
    ASSERT_FALSE(rows.empty());
    ASSERT_LT(saved.pairs_done, saved.pairs_total);
    const auto left = static_cast<double>(saved.pairs_total - saved.pairs_done);
    visibility::BakeCheckpoints resume;
    resume.resume = &saved;
    // Within the budget for the pairs left, though the whole bake would not be.
    ASSERT_LT(1.05 * left, 0.95 * static_cast<double>(saved.pairs_total));
    visibility::CellBakeStats stats;
    EXPECT_TRUE(visibility::bake_cell_visibility(corridor_scene(), grid(), config(), nullptr,
                                                 &stats, {}, {}, resume,
                                                 budget(1.05 * kMsPerPair * left)) == whole);
    EXPECT_NEAR(stats.predicted_seconds, kMsPerPair * left, 1e-9);
    try {
        (void)visibility::bake_cell_visibility(corridor_scene(), grid(), config(), nullptr, nullptr,
                                               {}, {}, resume, budget(0.95 * kMsPerPair * left));
        ADD_FAILURE() << "a bake over its budget finished";
    } catch (const visibility::BakeOverBudget& e) {
        EXPECT_NEAR(e.predicted_seconds, kMsPerPair * left, 1e-9);
    }
}

class BakeBudgetCache : public ::testing::Test {
protected:
    [[nodiscard]] BakeRequest request() const {
        BakeRequest r;
        r.config = config();
        r.dir = temp_.dir();
        r.checkpoint_seconds = 1e-6; // a save after every pair, one thread
        return r;
    }
    [[nodiscard]] std::vector<fs::path> partial_files() const {
        std::vector<fs::path> out;
        for (const auto& entry : fs::directory_iterator(temp_.dir())) {
            if (entry.path().extension() == ".partial") {
                out.push_back(entry.path());
            }
        }
        return out;
    }
    testing::TempDir temp_{"dsoc-budget-test-" +
                           std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name()};
};

TEST_F(BakeBudgetCache, CellsGrowPastEveryGridOverTheBudgetAndTheTableIsFoundNextTime) {
    BakeRequest r = request();
    r.max_bake_seconds = 1e-12; // on the real clock: every grid is over
    std::vector<float> said;
    r.gave_up = [&](const GridOverBudget& over) { said.push_back(over.cell_size); };
    const auto baked = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_TRUE(baked.ok()) << baked.error().message();
    EXPECT_FALSE(baked->from_cache);
    ASSERT_GE(baked->over_budget.size(), 2u);
    EXPECT_EQ(baked->over_budget.front().cell_size, 128.0f); // the memory budget's grid first
    EXPECT_EQ(said.size(), baked->over_budget.size());       // each said at once
    for (std::size_t i = 1; i < baked->over_budget.size(); ++i) {
        EXPECT_GT(baked->over_budget[i].cell_size, baked->over_budget[i - 1].cell_size);
    }
    for (const GridOverBudget& over : baked->over_budget) {
        EXPECT_LE(over.cell_size, 1024.0f);
        EXPECT_EQ(over.budget_seconds, 1e-12);
        EXPECT_NE(describe(over).find("over the 0 s budget"), std::string::npos) << describe(over);
    }
    // The first grid whose bake finished (a grid of one top pair finishes before it is
    // judged; the last, past 1024 units, is baked whatever it takes).
    EXPECT_GT(baked->table->grid().cell_size, baked->over_budget.back().cell_size);
    EXPECT_TRUE(fs::exists(baked->file));

    // With the default budget the table baked is taken from the cache, not baked again.
    r.max_bake_seconds = BakeRequest{}.max_bake_seconds;
    const auto again = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_TRUE(again.ok());
    EXPECT_TRUE(again->from_cache);
    EXPECT_EQ(again->file, baked->file);

    r.max_bake_seconds = 0.0;
    EXPECT_FALSE(load_or_bake(corridor(), corridor_scene(), r).ok());
}

TEST_F(BakeBudgetCache, AGridGivenUpLeavesNoPartialFileButOneTakenUpIsKept) {
    // Given up after a few pairs, each saved: its partial file is removed.
    BakeRequest r = request();
    r.budget_clock = FakeClock{}.function();
    r.budget_sample_fraction = 0.5;
    r.max_bake_seconds = 8 * kMsPerPair; // half of it is spent after 5 pairs
    const auto baked = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_TRUE(baked.ok()) << baked.error().message();
    ASSERT_FALSE(baked->over_budget.empty());
    EXPECT_GE(baked->over_budget.front().spent_seconds, 4 * kMsPerPair); // saves came first
    EXPECT_TRUE(partial_files().empty());

    // A bake of the first grid stopped part way, then taken up under a budget it
    // overruns: the cells grow, and the partial file stays for a larger budget.
    const testing::TempDir other("dsoc-budget-test-kept-" +
                                 std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    BakeRequest stopped = request();
    stopped.dir = other.dir();
    std::atomic<int> asked{0};
    stopped.stop = [&] { return ++asked >= 3; };
    ASSERT_FALSE(load_or_bake(corridor(), corridor_scene(), stopped).ok());
    std::vector<fs::path> kept;
    for (const auto& entry : fs::directory_iterator(other.dir())) {
        kept.push_back(entry.path());
    }
    ASSERT_EQ(kept.size(), 1u);
    ASSERT_EQ(kept.front().extension(), ".partial");
    BakeRequest taken_up = request();
    taken_up.dir = other.dir();
    taken_up.max_bake_seconds = 1e-12;
    const auto coarser = load_or_bake(corridor(), corridor_scene(), taken_up);
    ASSERT_TRUE(coarser.ok()) << coarser.error().message();
    ASSERT_FALSE(coarser->over_budget.empty());
    EXPECT_EQ(coarser->over_budget.front().cell_size, 128.0f);
    EXPECT_TRUE(fs::exists(kept.front()));
}

} // namespace
} // namespace dsoc::maps
