#include "dsoc/server/server_config.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace dsoc::server {
namespace {

TEST(ServerConfig, DefaultsAreValidOnceTokensAreDecided) {
    // Secure by default: a token key file, or an explicit insecure, is required.
    const auto problems = validate(ServerConfig{});
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].rfind("token_key_file:", 0), 0u) << problems[0];
    ServerConfig insecure;
    insecure.insecure = true;
    EXPECT_TRUE(validate(insecure).empty());
    ServerConfig keyed;
    keyed.token_key_file = "/etc/dsoc/token.key";
    EXPECT_TRUE(validate(keyed).empty());
}

TEST(ServerConfig, EachProblemNamesItsField) {
    ServerConfig c;
    c.insecure = true;
    c.tick_rate = 0;
    c.bots = -1;
    c.max_speed = std::nanf("");
    const auto problems = validate(c);
    ASSERT_EQ(problems.size(), 3u);
    EXPECT_NE(problems[0].find("tick_rate"), std::string::npos);
    EXPECT_NE(problems[1].find("bots"), std::string::npos);
    EXPECT_NE(problems[1].find("-1"), std::string::npos);
    EXPECT_NE(problems[2].find("max_speed"), std::string::npos);
}

TEST(ServerConfig, SoundSettingsAreCheckedWithTheirNames) {
    ServerConfig c;
    c.insecure = true;
    c.footstep_range = std::nanf("");
    c.shot_range = -1.0f;
    c.bot_shots_per_second = 1000.0f;
    c.heard_quantum = 0.25f; // finer than the far tier
    c.shot_damage = 101;     // more than an entity's health
    const auto problems = validate(c);
    ASSERT_EQ(problems.size(), 5u);
    for (const char* field :
         {"footstep_range", "shot_range", "bot_shots_per_second", "heard_quantum", "shot_damage"}) {
        EXPECT_TRUE(std::any_of(problems.begin(), problems.end(), [&](const std::string& p) {
            return p.find(field) != std::string::npos;
        })) << field;
    }
}

TEST(ServerConfig, InputCapMustLetAnHonestClientThrough) {
    ServerConfig c;
    c.insecure = true;
    c.tick_rate = 60;
    c.max_inputs_per_second = 61;
    const auto problems = validate(c);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].rfind("max_inputs_per_second: must be at least tick_rate + 2", 0), 0u)
        << problems[0];
    c.max_inputs_per_second = 62;
    EXPECT_TRUE(validate(c).empty());
}

/// Timers fire up to a gather late (io_loop.hpp): the gather stays within a quarter of
/// the tick period.
TEST(ServerConfig, TheIoThreadsGatherStaysWellWithinTheTickPeriod) {
    ServerConfig c;
    c.insecure = true;
    c.tick_rate = 30; // a quarter of the period: 8,333 µs
    c.io_gather_us = 8'333;
    EXPECT_TRUE(validate(c).empty());
    c.io_gather_us = 8'400;
    const auto problems = validate(c);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].rfind("io_gather_us: must be at most a quarter of the tick period", 0),
              0u)
        << problems[0];
    c.io_gather_us = 0; // wakes for each arrival
    EXPECT_TRUE(validate(c).empty());
    c.io_gather_us = -1;
    EXPECT_FALSE(validate(c).empty());
}

} // namespace
} // namespace dsoc::server
