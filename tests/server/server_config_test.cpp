#include "dsoc/server/server_config.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dsoc::server {
namespace {

TEST(ServerConfig, DefaultsAreValid) {
    EXPECT_TRUE(validate(ServerConfig{}).empty());
}

TEST(ServerConfig, EachProblemNamesItsField) {
    ServerConfig c;
    c.tick_rate = 0;
    c.policy = "psychic";
    c.max_speed = std::nanf("");
    const auto problems = validate(c);
    ASSERT_EQ(problems.size(), 3u);
    EXPECT_NE(problems[0].find("tick_rate"), std::string::npos);
    EXPECT_NE(problems[1].find("policy"), std::string::npos);
    EXPECT_NE(problems[1].find("psychic"), std::string::npos);
    EXPECT_NE(problems[2].find("max_speed"), std::string::npos);
}

} // namespace
} // namespace dsoc::server
