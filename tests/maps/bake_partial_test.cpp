// A bake that stops and goes on: a bake taken up from any saved state gives the table a
// bake that never stopped gives, bit for bit; the cache goes on from its partial file
// and removes it; a damaged, truncated, foreign or ill-fitting partial file is refused
// in one line and the bake starts from the beginning.

#include "dsoc/maps/bake_cache.hpp"
#include "dsoc/maps/bake_file.hpp"
#include "dsoc/maps/bake_partial.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace dsoc::maps {
namespace {

namespace fs = std::filesystem;

struct Saved {
    std::uint64_t pairs_done;
    std::uint64_t pairs_total;
    std::vector<std::uint64_t> rows;
    visibility::CellBakeStats stats;
    [[nodiscard]] visibility::BakeState state() const {
        return {pairs_done, pairs_total, rows, stats};
    }
};

const Map& corridor() {
    return test::shared_corridor().map;
}
const visibility::OccluderScene& corridor_scene() {
    return *test::shared_corridor().scene;
}

visibility::CellBakeConfig config(int threads) {
    visibility::CellBakeConfig c;
    c.cell_size = 128.0f; // coarse: a few hundred top pairs
    c.threads = threads;
    c.top_level = 1; // many top pairs, so that saves fall between them
    return c;
}

TEST(PartialBake, ABakeTakenUpFromAnySavedStateGivesTheSameTable) {
    const auto grid =
        bake_grid(corridor(), corridor_scene(), 128.0f, std::uint64_t{128} << 20, std::nullopt);
    visibility::CellBakeStats whole_stats;
    const auto whole =
        visibility::bake_cell_visibility(corridor_scene(), grid, config(2), nullptr, &whole_stats);
    ASSERT_GT(whole.hidden_pairs(), 0u); // the table does hide something
    std::vector<Saved> saved;
    visibility::BakeCheckpoints every_round;
    every_round.interval_seconds = 1e-6; // a save between every few pairs
    std::uint64_t last_done = 0;
    int rounds = 0;
    every_round.save = [&](const visibility::BakeState& s) {
        EXPECT_GT(s.pairs_done, last_done); // every round moves on
        last_done = s.pairs_done;
        if (rounds++ % 16 == 0) { // keep a few
            saved.push_back({s.pairs_done, s.pairs_total, {s.rows.begin(), s.rows.end()}, s.stats});
        }
    };
    const auto checkpointed = visibility::bake_cell_visibility(
        corridor_scene(), grid, config(2), nullptr, nullptr, {}, {}, every_round);
    EXPECT_TRUE(checkpointed == whole);
    ASSERT_GE(saved.size(), 3u);
    for (const Saved* s : {&saved.front(), &saved[saved.size() / 2], &saved.back()}) {
        ASSERT_GT(s->pairs_done, 0u);
        ASSERT_LT(s->pairs_done, s->pairs_total);
        const visibility::BakeState state = s->state();
        visibility::BakeCheckpoints resume;
        resume.resume = &state;
        for (const int threads : {1, 2}) {
            visibility::CellBakeStats stats;
            const auto resumed = visibility::bake_cell_visibility(
                corridor_scene(), grid, config(threads), nullptr, &stats, {}, {}, resume);
            EXPECT_TRUE(resumed == whole) << "resumed at " << s->pairs_done << " of "
                                          << s->pairs_total << " on " << threads << " threads";
            EXPECT_EQ(stats.pair_visits, whole_stats.pair_visits);
            EXPECT_EQ(stats.exact_tests, whole_stats.exact_tests);
            EXPECT_EQ(stats.witness_rays, whole_stats.witness_rays);
            EXPECT_EQ(stats.open_cells, whole_stats.open_cells);
        }
    }
    // A state of another bake is refused, not taken.
    Saved wrong = saved.front();
    wrong.rows.pop_back();
    const visibility::BakeState wrong_state = wrong.state();
    visibility::BakeCheckpoints bad;
    bad.resume = &wrong_state;
    EXPECT_THROW((void)visibility::bake_cell_visibility(corridor_scene(), grid, config(1), nullptr,
                                                        nullptr, {}, {}, bad),
                 std::invalid_argument);
}

class PartialBakeFile : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("dsoc-partial-test-" +
                std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    [[nodiscard]] BakeRequest request(const fs::path& dir) const {
        BakeRequest r;
        r.config = config(2);
        r.dir = dir;
        r.checkpoint_seconds = 1e-6;
        return r;
    }
    /// Bakes into dir_ until the third save, leaving the partial file; returns its path.
    [[nodiscard]] fs::path stopped_bake() const {
        BakeRequest r = request(dir_);
        std::atomic<int> asked{0}; // by the bake's watcher and after each save
        r.stop = [&] { return ++asked >= 3; };
        const auto stopped = load_or_bake(corridor(), corridor_scene(), r);
        EXPECT_FALSE(stopped.ok());
        const std::string message = stopped.ok() ? "" : stopped.error().message();
        EXPECT_NE(message.find("bake stopped at"), std::string::npos) << message;
        for (const auto& entry : fs::directory_iterator(dir_)) {
            if (entry.path().extension() == ".partial") {
                return entry.path();
            }
        }
        ADD_FAILURE() << "no partial file in " << dir_;
        return {};
    }
    /// The table of a bake that never stopped (in a directory of its own).
    [[nodiscard]] BakedTable fresh() const {
        auto r = request(dir_ / "fresh");
        r.checkpoint_seconds = 0.0;
        auto baked = load_or_bake(corridor(), corridor_scene(), r);
        EXPECT_TRUE(baked.ok());
        return std::move(baked).value();
    }

    fs::path dir_;
};

TEST_F(PartialBakeFile, TheCacheGoesOnFromItsPartialFileAndRemovesIt) {
    const fs::path partial = stopped_bake();
    ASSERT_TRUE(fs::exists(partial));
    const auto went_on = load_or_bake(corridor(), corridor_scene(), request(dir_));
    ASSERT_TRUE(went_on.ok()) << went_on.error().message();
    EXPECT_GT(went_on->resumed_fraction, 0.0);
    EXPECT_LT(went_on->resumed_fraction, 1.0);
    EXPECT_TRUE(went_on->cache_problem.empty()) << went_on->cache_problem;
    EXPECT_FALSE(fs::exists(partial)); // removed once the table is written
    EXPECT_TRUE(*went_on->table == *fresh().table);
    EXPECT_TRUE(read_bake_file(went_on->file, went_on->key).ok());
}

TEST_F(PartialBakeFile, AStopAsksForASaveAtOnceAndTheNextBakeGoesOnFromIt) {
    // Saves an hour apart: only the stop (a signal to dsoc-bake) brings one about.
    BakeRequest r = request(dir_);
    r.checkpoint_seconds = 3600.0;
    r.stop = [] { return true; };
    const auto stopped = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_FALSE(stopped.ok());
    EXPECT_NE(stopped.error().message().find("goes on from there next time"), std::string::npos)
        << stopped.error().message();
    r.stop = nullptr;
    const auto went_on = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_TRUE(went_on.ok()) << went_on.error().message();
    EXPECT_GT(went_on->resumed_fraction, 0.0); // each worker resolved a pair first
    EXPECT_LT(went_on->resumed_fraction, 1.0);
    EXPECT_TRUE(*went_on->table == *fresh().table);
}

TEST_F(PartialBakeFile, AStopEndsABakeThatSavesNothingAndSaysSo) {
    BakeRequest r = request(dir_);
    r.checkpoint_seconds = 0.0; // no partial file
    r.stop = [] { return true; };
    const auto stopped = load_or_bake(corridor(), corridor_scene(), r);
    ASSERT_FALSE(stopped.ok()); // not baked to the end regardless
    EXPECT_NE(stopped.error().message().find("nothing kept (checkpoint_seconds is 0)"),
              std::string::npos)
        << stopped.error().message();
    EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(PartialBakeFile, ADamagedPartialFileIsRefusedInOneLineAndTheBakeStartsOver) {
    const auto expected = fresh();
    const fs::path partial = stopped_bake();
    const auto original = read_cache_file(partial);
    ASSERT_TRUE(original.ok());
    const auto bytes = original.value();
    std::uint64_t key; // at offset 16 (docs/baked-visibility.md)
    std::memcpy(&key, bytes.data() + 16, sizeof key);
    struct Damage {
        const char* what;
        std::vector<std::byte> bytes;
        const char* says;
    };
    std::vector<Damage> damages;
    auto flipped = bytes;
    flipped[flipped.size() - 3] ^= std::byte{0x10};
    damages.push_back({"a flipped bit", flipped, "checksum"});
    damages.push_back(
        {"truncated", std::vector<std::byte>(bytes.begin(), bytes.end() - 8), "truncated"});
    damages.push_back(
        {"not a partial file", std::vector<std::byte>(300, std::byte{7}), "DSOCPART"});
    // Checksummed and of this key, but of another size or with bits past the last open
    // cell: what only a forger or a bug could write.
    auto decoded = decode_partial(bytes, partial.string(), key);
    ASSERT_TRUE(decoded.ok()) << decoded.error().message();
    PartialBake shorter = decoded.value();
    shorter.rows.pop_back();
    damages.push_back({"rows of another bake", encode_partial(shorter.state(), key), "do not fit"});
    ASSERT_NE(expected.table->open_count() % 64, 0u); // so that a row's last word has room
    PartialBake past = decoded.value();
    past.rows.assign(past.rows.size(), ~std::uint64_t{0});
    damages.push_back({"bits past the last cell", encode_partial(past.state(), key), "bits past"});
    for (const Damage& d : damages) {
        std::ofstream(partial, std::ios::binary | std::ios::trunc)
            .write(reinterpret_cast<const char*>(d.bytes.data()),
                   static_cast<std::streamsize>(d.bytes.size()));
        const auto again = load_or_bake(corridor(), corridor_scene(), request(dir_));
        ASSERT_TRUE(again.ok()) << d.what;
        EXPECT_EQ(again->resumed_fraction, 0.0) << d.what;
        EXPECT_NE(again->cache_problem.find(partial.string()), std::string::npos)
            << d.what << ": " << again->cache_problem;
        EXPECT_NE(again->cache_problem.find(d.says), std::string::npos)
            << d.what << ": " << again->cache_problem;
        EXPECT_NE(again->cache_problem.find("baking from the start"), std::string::npos)
            << again->cache_problem;
        EXPECT_EQ(again->cache_problem.find('\n'), std::string::npos);
        EXPECT_TRUE(*again->table == *expected.table) << d.what;
        EXPECT_FALSE(fs::exists(partial)) << d.what;
        fs::remove(again->file); // the next damage starts without a table
    }
    // A partial file of another key is refused by the reader.
    const auto foreign = decode_partial(bytes, partial.string(), key + 1);
    ASSERT_FALSE(foreign.ok());
    EXPECT_NE(foreign.error().message().find("another map"), std::string::npos)
        << foreign.error().message();
}

} // namespace
} // namespace dsoc::maps
