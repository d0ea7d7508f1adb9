// A short dsoc-eval run (the "tiny" scenario's size): the replication trace it writes
// is valid against the spec, an outside check of that trace finds no pop-in for dsoc,
// and dsoc culls something.

#include "dsoc/eval/evaluation.hpp"
#include "dsoc/eval/ray_oracle.hpp"
#include "dsoc/eval/world_sim.hpp"
#include "dsoc/trace/trace_reader.hpp"

#include "support/temp_dir.hpp"
#include "support/trace_checks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace dsoc::eval {
namespace {

Scenario tiny_scenario() {
    Scenario s;
    s.name = "test-tiny";
    s.map = "gen:rooms";
    s.viewers = 4;
    s.bots = 24;
    s.tick_rate = 30;
    s.rtt_ms = 100;
    s.interpolation_ms = 50;
    s.duration_s = 3.0;
    s.oracle_every = 1;
    s.seed = 3;
    return s;
}

const PolicyMetrics& find(const EvalResult& r, const std::string& name) {
    for (const auto& m : r.policies) {
        if (m.name == name) {
            return m;
        }
    }
    throw std::runtime_error("no policy " + name);
}

TEST(EvalRun, TraceFollowsTheSpecAndDsocHasNoPopIn) {
    const std::string path = testing::run_temp_path("dsoc-eval-test", ".jsonl");
    EvalOptions options;
    options.scenario = tiny_scenario();
    options.policies = {"broadcast", "occlusion", "dsoc", "raycast"};
    options.trace_path = path;
    options.trace_every = 1;
    const EvalResult result = run_evaluation(options, nullptr);

    const int K = options.scenario.lookahead_ticks();
    ASSERT_EQ(K, 5);
    ASSERT_EQ(result.ticks, 90);
    EXPECT_EQ(result.oracle_client_ticks, 90u * 4u);
    EXPECT_EQ(result.trace_policy, "dsoc");
    EXPECT_EQ(result.trace_ticks, 90u);

    const PolicyMetrics& dsoc = find(result, "dsoc");
    const PolicyMetrics& broadcast = find(result, "broadcast");
    EXPECT_EQ(dsoc.popin_present, 0u);
    EXPECT_EQ(dsoc.popin_lookahead, 0u);
    EXPECT_EQ(find(result, "occlusion").popin_present, 0u);
    EXPECT_EQ(broadcast.popin_lookahead, 0u);
    EXPECT_LT(dsoc.replicated_pairs, broadcast.replicated_pairs) << "dsoc culls nothing";
    EXPECT_GT(dsoc.bytes, 0u);
    EXPECT_GT(result.ideal_bytes, 0u);

    // Read the trace back with the spec's reader and check its fields.
    trace::TraceReader reader;
    ASSERT_TRUE(reader.open(path)) << reader.error();
    const maps::Map map = load_scenario_map(options.scenario);
    EXPECT_EQ(reader.header().map, map.name);
    EXPECT_EQ(reader.header().tick_rate, 30);
    EXPECT_EQ(reader.header().policy, "dsoc");
    EXPECT_EQ(reader.header().lookahead_ticks, K);
    ASSERT_EQ(reader.header().occluders.size(), map.occluders.size());
    std::vector<trace::TraceTick> ticks;
    trace::TraceTick tick;
    while (reader.next(tick)) {
        ticks.push_back(tick);
    }
    ASSERT_TRUE(reader.error().empty()) << reader.error();
    ASSERT_TRUE(reader.finished());
    ASSERT_EQ(ticks.size(), 90u);
    for (std::size_t i = 0; i < ticks.size(); ++i) {
        const auto& t = ticks[i];
        EXPECT_EQ(t.t, i);
        ASSERT_EQ(t.entities.size(), 28u);
        ASSERT_EQ(t.clients.size(), 4u);
        for (const auto& c : t.clients) {
            ASSERT_TRUE(c.entity.has_value());
            EXPECT_EQ(*c.entity, c.id);
            EXPECT_TRUE(std::is_sorted(c.replicated.begin(), c.replicated.end()));
            EXPECT_EQ(std::count(c.replicated.begin(), c.replicated.end(), c.id), 0);
            // The eye is inside the client's own entity box.
            const auto& own = t.entities[c.id];
            EXPECT_EQ(own.id, c.id);
            EXPECT_TRUE(own.box.contains(c.eye));
        }
    }

    // An outside checker, as the spec describes it, from the trace alone: the Embree
    // oracle over the header's half-spaces (rebuilt as polyhedra), eyes of ticks
    // t .. t + K.
    std::vector<visibility::ConvexPolyhedron> solids;
    for (const auto& o : reader.header().occluders) {
        visibility::PolyhedronResult r;
        solids.push_back(visibility::ConvexPolyhedron::from_planes(o.planes, r));
    }
    const RayOracle oracle(solids);
    std::size_t violations = 0;
    std::size_t hidden_pairs = 0;
    for (std::size_t i = 0; i < ticks.size(); ++i) {
        for (std::size_t ci = 0; ci < ticks[i].clients.size(); ++ci) {
            const auto& c = ticks[i].clients[ci];
            for (const auto& e : ticks[i].entities) {
                if (e.id == c.id ||
                    std::binary_search(c.replicated.begin(), c.replicated.end(), e.id)) {
                    continue;
                }
                ++hidden_pairs;
                for (std::size_t k = i; k < ticks.size() && k <= i + static_cast<std::size_t>(K);
                     ++k) {
                    if (oracle.box_visible(ticks[k].clients[ci].eye, e.box, 5)) {
                        ++violations;
                        ADD_FAILURE()
                            << "pop-in: tick " << ticks[i].t << " client " << c.id << " entity "
                            << e.id << " visible from the eye of tick " << ticks[k].t;
                        break;
                    }
                }
            }
        }
    }
    EXPECT_EQ(violations, 0u);
    EXPECT_GT(hidden_pairs, 0u);
    std::filesystem::remove(path);
}

} // namespace
} // namespace dsoc::eval

namespace dsoc::eval {
namespace {

TEST(EvalRun, WithTeamsEveryPolicySendsTeammatesAndTheOracleJudgesTheOtherPairs) {
    const std::string path = testing::run_temp_path("dsoc-eval-teams", ".jsonl");
    EvalOptions options;
    options.scenario = tiny_scenario();
    options.scenario.teams = 2;
    options.scenario.duration_s = 1.0;
    options.policies = {"distance", "dsoc", "raycast"};
    options.trace_path = path;
    options.trace_every = 1;
    const EvalResult with_teams = run_evaluation(options, nullptr);
    options.scenario.teams = 0;
    options.trace_path.clear();
    const EvalResult without = run_evaluation(options, nullptr);
    for (const char* name : {"distance", "dsoc", "raycast"}) {
        const PolicyMetrics& m = find(with_teams, name);
        EXPECT_GT(m.checked_by_rule, 0u) << name;
        EXPECT_EQ(m.missed_by_rule, 0u) << name << " left a teammate out";
        EXPECT_EQ(find(without, name).checked_by_rule, 0u) << name;
    }
    EXPECT_EQ(find(with_teams, "dsoc").popin_lookahead, 0u);
    // The raycast policy hides some teammates by sight alone: with teams it sends more.
    EXPECT_GT(find(with_teams, "raycast").replicated_pairs,
              find(without, "raycast").replicated_pairs);
    // The trace says which entities each client got for its team.
    trace::TraceReader reader;
    ASSERT_TRUE(reader.open(path)) << reader.error();
    trace::TraceTick tick;
    ASSERT_TRUE(reader.next(tick)) << reader.error();
    for (const trace::TraceClient& c : tick.clients) {
        ASSERT_FALSE(c.always.empty()) << "client " << c.id;
        for (const std::uint32_t id : c.always) {
            EXPECT_EQ(id % 2, c.id % 2) << "client " << c.id << " entity " << id;
            EXPECT_NE(id, c.id);
            EXPECT_TRUE(std::binary_search(c.replicated.begin(), c.replicated.end(), id))
                << "client " << c.id << " entity " << id;
        }
    }
    std::filesystem::remove(path);
}

TEST(EvalRun, WithSoundsHeardOnlyEntitiesAreCoarseAndJudgedApartFromSight) {
    // The same world with and without sounds (sounds move nothing): with them every
    // policy sends more, the extra entities are heard-only (coarse, judged apart), dsoc
    // still pops nothing in, and no heard-only entity is one the oracle sees.
    const std::string path = testing::run_temp_path("dsoc-eval-sounds", ".jsonl");
    EvalOptions options;
    options.scenario = tiny_scenario();
    options.scenario.sounds = true;
    options.scenario.duration_s = 1.0;
    options.policies = {"raycast", "dsoc"};
    options.trace_path = path;
    options.trace_every = 1;
    const EvalResult loud = run_evaluation(options, nullptr);
    options.scenario.sounds = false;
    options.trace_path.clear();
    const EvalResult silent = run_evaluation(options, nullptr);
    for (const char* name : {"raycast", "dsoc"}) {
        const PolicyMetrics& m = find(loud, name);
        const PolicyMetrics& s = find(silent, name);
        EXPECT_GT(m.heard_pairs, 0u) << name;
        EXPECT_EQ(m.replicated_pairs, s.replicated_pairs + m.heard_pairs) << name;
        EXPECT_GT(m.heard_entries, 0u) << name;
        EXPECT_GT(m.bytes, m.sight_bytes) << name;
        EXPECT_EQ(m.sight_bytes, s.bytes) << name << ": without the heard ones, the same bytes";
        EXPECT_GT(m.checked_heard, 0u) << name;
        EXPECT_EQ(s.heard_pairs, 0u) << name;
    }
    EXPECT_EQ(find(loud, "dsoc").popin_lookahead, 0u);
    EXPECT_EQ(find(loud, "dsoc").heard_visible, 0u);
    EXPECT_GT(testing::expect_heard_are_replicated(path), 0u);
    std::filesystem::remove(path);
}

} // namespace
} // namespace dsoc::eval
