// Issue 5's acceptance run: DSOC on a real map with walking bots and walking viewers,
// judged every tick by the independent Embree ray oracle over more than 20,000
// client-ticks: zero pop-in from the present eye and within the latency allowance,
// and a large share of entities culled.

#include "dsoc/eval/evaluation.hpp"
#include "support/openarena.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

namespace dsoc::eval {
namespace {

/// Walking viewers and bots at 30 Hz with a 100 ms round trip and 50 ms of
/// interpolation, every tick judged by the oracle.
EvalOptions judged_every_tick(const char* name, const char* map, int viewers, int bots,
                              double seconds, std::uint64_t seed) {
    EvalOptions options;
    Scenario& s = options.scenario;
    s.name = name;
    s.map = map;
    s.viewers = viewers;
    s.bots = bots;
    s.tick_rate = 30;
    s.rtt_ms = 100;
    s.interpolation_ms = 50;
    s.duration_s = seconds;
    s.oracle_every = 1;
    s.seed = seed;
    options.dsoc_overrides = {"validate_state=true"}; // ValidateDSOCState every tick
    return options;
}

void expect_no_popin_and_culling(const std::vector<PolicyMetrics>& policies, const std::string& map,
                                 double max_kept) {
    const PolicyMetrics* broadcast = nullptr;
    for (const auto& m : policies) {
        broadcast = m.name == "broadcast" ? &m : broadcast;
    }
    ASSERT_NE(broadcast, nullptr);
    for (const auto& m : policies) {
        if (m.name == "broadcast") {
            continue;
        }
        EXPECT_EQ(m.popin_present, 0u) << m.name;
        EXPECT_EQ(m.popin_lookahead, 0u) << m.name;
        const double kept = static_cast<double>(m.replicated_pairs) /
                            static_cast<double>(broadcast->replicated_pairs);
        EXPECT_LT(kept, max_kept) << m.name;
        std::printf("%s on %s: pop-in %llu / %llu, keeps %.1f%% of broadcast's pairs\n",
                    m.name.c_str(), map.c_str(), static_cast<unsigned long long>(m.popin_present),
                    static_cast<unsigned long long>(m.popin_lookahead), kept * 100.0);
    }
}

TEST(DsocOnARealMap, ZeroPopInOverTwentyThousandClientTicks) {
    DSOC_REQUIRE_OPENARENA();
    // 630 ticks x 32 viewers = 20,160 client-ticks
    EvalOptions options = judged_every_tick("dsoc-acceptance", "oa_dm4", 32, 96, 21.0, 17);
    // dsoc as the server runs it without a table (no TBVs), and with the paper's TBVs.
    options.policies = {"broadcast", "dsoc", "dsoc-tbvs"};
    const EvalResult result = run_evaluation(options, nullptr);

    ASSERT_GE(result.oracle_client_ticks, 20000u);
    // A large share of entities is culled: at least 40% fewer replicated pairs than
    // broadcasting (arena-64 measures about 50%).
    expect_no_popin_and_culling(result.policies, "oa_dm4", 0.6);
    for (const auto& m : result.policies) {
        if (m.name == "dsoc-tbvs") {
            EXPECT_GT(m.tbv.tbvs_created, 1000u) << "the TBVs under test were never made";
        }
    }
}

TEST(DsocWithoutAPvs, ZeroPopInOnAGeneratedCityWithEntityClusters) {
    // gen:city has no PVS: every hidden entity is proven by the shaft stage (with
    // fusion), crowds by their cluster's box, and with TBVs (dsoc-tbvs) their TBVs are
    // shared group TBVs.
    // 180 ticks x 16 viewers = 2,880 client-ticks
    EvalOptions options = judged_every_tick("dsoc-city", "gen:city", 16, 600, 6.0, 23);
    options.scenario.city_blocks = 6;
    options.policies = {"broadcast", "occlusion", "dsoc", "dsoc-tbvs"};
    const EvalResult result = run_evaluation(options, nullptr);

    ASSERT_GE(result.oracle_client_ticks, 2800u);
    for (const auto& m : result.policies) {
        if (m.name == "broadcast") {
            continue;
        }
        EXPECT_EQ(m.popin_present, 0u) << m.name;
        EXPECT_EQ(m.popin_lookahead, 0u) << m.name;
        EXPECT_GT(m.tbv.cluster_hits, 1000u) << m.name << ": clusters never hid a crowd";
        std::printf("%s on gen:city:6: pop-in %llu / %llu, %llu of %llu cluster tests hidden\n",
                    m.name.c_str(), static_cast<unsigned long long>(m.popin_present),
                    static_cast<unsigned long long>(m.popin_lookahead),
                    static_cast<unsigned long long>(m.tbv.cluster_hits),
                    static_cast<unsigned long long>(m.tbv.cluster_tests));
    }
}

TEST(DsocOnARealMap, ZeroPopInWhenHalfTheClientTicksGetTheCheapestAnswer) {
    DSOC_REQUIRE_OPENARENA();
    // The server's fail-open, emulated: half the client-ticks over budget get the
    // culler's prepared stage alone (the map's PVS). 120 ticks x 32 viewers.
    EvalOptions options = judged_every_tick("dsoc-fail-open", "oa_dm4", 32, 96, 4.0, 31);
    options.policies = {"broadcast", "dsoc"};
    const EvalResult full = run_evaluation(options, nullptr);
    options.cheapest_share = 0.5;
    const EvalResult loaded = run_evaluation(options, nullptr);
    const auto metrics = [](const EvalResult& r, const char* name) {
        for (const auto& m : r.policies) {
            if (m.name == name) {
                return m;
            }
        }
        ADD_FAILURE() << "no " << name;
        return PolicyMetrics{};
    };
    const PolicyMetrics dsoc_full = metrics(full, "dsoc");
    const PolicyMetrics dsoc_loaded = metrics(loaded, "dsoc");
    const PolicyMetrics broadcast = metrics(loaded, "broadcast");
    EXPECT_EQ(dsoc_loaded.popin_present, 0u);
    EXPECT_EQ(dsoc_loaded.popin_lookahead, 0u);
    // About half the client-ticks were degraded, and counted.
    const auto client_ticks = static_cast<double>(loaded.oracle_client_ticks);
    EXPECT_GT(static_cast<double>(dsoc_loaded.tbv.cheapest_updates), 0.4 * client_ticks);
    EXPECT_LT(static_cast<double>(dsoc_loaded.tbv.cheapest_updates), 0.6 * client_ticks);
    EXPECT_EQ(dsoc_full.tbv.cheapest_updates, 0u);
    // Looser than the full answer, and still culling.
    EXPECT_GT(dsoc_loaded.replicated_pairs, dsoc_full.replicated_pairs);
    EXPECT_LT(dsoc_loaded.replicated_pairs, broadcast.replicated_pairs * 8 / 10);
    std::printf("dsoc on oa_dm4 with half its client-ticks at the cheapest effort: pop-in "
                "%llu / %llu, %llu pairs (full effort %llu, broadcast %llu)\n",
                static_cast<unsigned long long>(dsoc_loaded.popin_present),
                static_cast<unsigned long long>(dsoc_loaded.popin_lookahead),
                static_cast<unsigned long long>(dsoc_loaded.replicated_pairs),
                static_cast<unsigned long long>(dsoc_full.replicated_pairs),
                static_cast<unsigned long long>(broadcast.replicated_pairs));
}

/// dsoc-baked (the baked table, then the exact stages) and dsoc-table (the table
/// alone) judged every tick; returns the metrics by name.
std::vector<PolicyMetrics> run_baked(EvalOptions options, const std::string& tag) {
    const auto dir = std::filesystem::temp_directory_path() / ("dsoc-eval-bakes-" + tag);
    std::filesystem::remove_all(dir);
    options.bake_dir = dir.string();
    options.policies = {"broadcast", "dsoc-baked", "dsoc-table"};
    const EvalResult result = run_evaluation(options, nullptr);
    std::filesystem::remove_all(dir);
    EXPECT_GE(result.oracle_client_ticks, 5000u);
    return result.policies;
}

TEST(DsocOnARealMap, ZeroPopInWithTheBakedStage) {
    DSOC_REQUIRE_OPENARENA();
    // 240 ticks x 32 viewers = 7,680 client-ticks
    EvalOptions options = judged_every_tick("dsoc-baked-acceptance", "oa_dm4", 32, 96, 8.0, 19);
    options.bake_cell_size = 64.0f; // bakes in seconds; the figures use 32
    expect_no_popin_and_culling(run_baked(options, "oa_dm4"), "oa_dm4", 0.75);
}

TEST(DsocWithoutAPvs, ZeroPopInWithTheBakedStageOnAGeneratedCity) {
    // No PVS: the table comes from the brushes alone.
    // 330 ticks x 16 viewers = 5,280 client-ticks
    EvalOptions options = judged_every_tick("dsoc-baked-city", "gen:city", 16, 300, 11.0, 29);
    options.scenario.city_blocks = 4;
    options.bake_cell_size = 128.0f; // an open city: coarse cells keep the bake short
    expect_no_popin_and_culling(run_baked(options, "city"), "gen:city:4", 0.9);
}

} // namespace
} // namespace dsoc::eval
