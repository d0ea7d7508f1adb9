// Scenarios: the client count over the stages, the groups' shares, and the TOML file.

#include "dsoc/simclient/scenario.hpp"
#include "dsoc/simclient/scenario_file.hpp"

#include <gtest/gtest.h>

namespace dsoc::simclient {
namespace {

TEST(Scenario, TargetFollowsRampHoldAndRampDown) {
    const std::vector<Stage> stages = {{2.0, 10}, {3.0, 10}, {1.0, 0}};
    EXPECT_EQ(target_at(stages, 0.0), 0);
    EXPECT_EQ(target_at(stages, 0.01), 1); // rounded up: the first client starts at once
    EXPECT_EQ(target_at(stages, 1.0), 5);
    EXPECT_EQ(target_at(stages, 1.99), 10);
    EXPECT_EQ(target_at(stages, 2.0), 10);
    EXPECT_EQ(target_at(stages, 4.99), 10);
    EXPECT_EQ(target_at(stages, 5.5), 5);
    EXPECT_EQ(target_at(stages, 5.99), 1);
    EXPECT_EQ(target_at(stages, 6.0), 0); // past the end
    // A stage of 0 s jumps.
    EXPECT_EQ(target_at({{0.0, 7}, {1.0, 7}}, 0.0), 7);
}

TEST(Scenario, ThePlainFlagsAreOneRampAndOneHold) {
    const Scenario s = implicit_scenario(32, 15.0, 1.0);
    ASSERT_EQ(s.stages.size(), 2u);
    EXPECT_DOUBLE_EQ(s.length_s(), 15.0);
    EXPECT_EQ(s.peak_target(), 32);
    EXPECT_EQ(target_at(s.stages, 0.5), 16);
    EXPECT_EQ(target_at(s.stages, 14.9), 32);
    ASSERT_EQ(s.groups.size(), 1u);
    EXPECT_EQ(s.groups[0].behaviour, Behaviour::wanderer);
    EXPECT_EQ(validate(s), "");
}

TEST(Scenario, GroupsShareTheCountByWeight) {
    std::vector<ClientGroup> groups(3);
    groups[0].weight = 2.0;
    groups[1].weight = 1.0;
    groups[2].weight = 1.0;
    EXPECT_EQ(split_by_weight(8, groups), (std::vector<int>{4, 2, 2}));
    EXPECT_EQ(split_by_weight(5, groups), (std::vector<int>{3, 1, 1}));
    EXPECT_EQ(split_by_weight(1, groups), (std::vector<int>{1, 0, 0}));
    EXPECT_EQ(split_by_weight(0, groups), (std::vector<int>{0, 0, 0}));
    for (int n = 0; n < 50; ++n) {
        const auto shares = split_by_weight(n, groups);
        EXPECT_EQ(shares[0] + shares[1] + shares[2], n);
    }
}

constexpr const char* kScenario = R"(
connect_timeout = "2s"
thresholds = ["interarrival_p99 < 50ms", "failure_rate < 1%"]
stages = [
  { duration = "2s", target = 6 },
  { duration = "1m", target = 6 },
  { duration = 1.5, target = 0 },
]

[[groups]]
name = "runners"
weight = 2
churn_per_s = 0.5

[[groups]]
name = "campers"
behaviour = "camper"
latency = "40ms"
jitter = "5ms"
loss = 0.05
reorder = 0.01

[[groups]]
behaviour = "respawner"
respawn_every = "8s"
)";

TEST(ScenarioFile, ReadsStagesGroupsAndThresholds) {
    Scenario s;
    std::string error;
    ASSERT_TRUE(parse_scenario(kScenario, "test.toml", s, error)) << error;
    ASSERT_EQ(s.stages.size(), 3u);
    EXPECT_DOUBLE_EQ(s.stages[1].duration_s, 60.0);
    EXPECT_DOUBLE_EQ(s.stages[2].duration_s, 1.5);
    EXPECT_EQ(s.stages[2].target, 0);
    EXPECT_DOUBLE_EQ(s.length_s(), 63.5);
    EXPECT_DOUBLE_EQ(s.connect_timeout_s, 2.0);
    ASSERT_EQ(s.groups.size(), 3u);
    EXPECT_EQ(s.groups[0].name, "runners");
    EXPECT_EQ(s.groups[0].behaviour, Behaviour::wanderer);
    EXPECT_DOUBLE_EQ(s.groups[0].weight, 2.0);
    EXPECT_DOUBLE_EQ(s.groups[0].churn_per_s, 0.5);
    EXPECT_EQ(s.groups[1].behaviour, Behaviour::camper);
    EXPECT_DOUBLE_EQ(s.groups[1].network.latency_ms, 40.0);
    EXPECT_DOUBLE_EQ(s.groups[1].network.jitter_ms, 5.0);
    EXPECT_DOUBLE_EQ(s.groups[1].network.faults.loss, 0.05);
    EXPECT_DOUBLE_EQ(s.groups[1].network.faults.duplicate, 0.0);
    EXPECT_DOUBLE_EQ(s.groups[1].network.faults.reorder, 0.01);
    EXPECT_FALSE(s.groups[0].network.faults.any());
    EXPECT_EQ(s.groups[2].name, "group-3");
    EXPECT_EQ(s.groups[2].behaviour, Behaviour::respawner);
    EXPECT_DOUBLE_EQ(s.groups[2].respawn_every_s, 8.0);
    ASSERT_EQ(s.thresholds.size(), 2u);
    EXPECT_EQ(s.thresholds[1].figure, "failure_rate");
}

std::string file_error(const std::string& text) {
    Scenario s;
    std::string error;
    EXPECT_FALSE(parse_scenario(text, "s.toml", s, error)) << text;
    return error;
}

TEST(ScenarioFile, NamesWhereAndWhatIsWrong) {
    EXPECT_EQ(file_error("stages = [{ duration = \"1s\", target = 2 }]\nclients = 3\n"),
              "s.toml:2:11: clients: unknown key; known: stages, groups, thresholds, "
              "connect_timeout");
    EXPECT_EQ(file_error("stages = [{ duration = \"1s\" }]\n"),
              "s.toml:1:11: stages[0]: a stage needs duration and target ({ duration = \"5s\", "
              "target = 10 })");
    EXPECT_NE(file_error("stages = [{ duration = \"1 fortnight\", target = 2 }]\n")
                  .find("s.toml:1:24: stages[0].duration: '1 fortnight': unknown unit"),
              std::string::npos);
    EXPECT_NE(file_error("stages = [{ duration = \"1s\", target = 2 }]\n[[groups]]\n"
                         "behaviour = \"sniper\"\n")
                  .find("s.toml:3:13: groups[0].behaviour: unknown behaviour 'sniper'; known: "
                        "wanderer, camper, respawner"),
              std::string::npos);
    EXPECT_NE(file_error("stages = [{ duration = \"1s\", target = 2 }]\n"
                         "thresholds = [\"latency<5ms\"]\n")
                  .find("s.toml:2:15: thresholds[0]: threshold 'latency<5ms': unknown figure"),
              std::string::npos);
    EXPECT_EQ(file_error("thresholds = []\n"), "s.toml: stages: at least one stage is needed");
    EXPECT_EQ(file_error("stages = [{ duration = \"1s\", target = 2 }]\n"
                         "[[groups]]\nname = \"a\"\n[[groups]]\nname = \"a\"\n"),
              "s.toml: group 'a': the name is used twice");
    EXPECT_NE(file_error("stages = [").find("s.toml:1:"), std::string::npos);
    EXPECT_NE(file_error("stages = [{ duration = \"1s\", target = 2 }]\n[[groups]]\n"
                         "loss = 1.5\n")
                  .find("groups[0].loss: must be a probability 0..0.9 (UDP only)"),
              std::string::npos);
}

} // namespace
} // namespace dsoc::simclient
