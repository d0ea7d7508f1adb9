// dsoc-server's JSON log lines (--log-format json): one valid JSON object a line,
// whatever the message holds.

#include "dsoc/server/logging.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <spdlog/details/log_msg.h>

#include <chrono>
#include <string>

namespace dsoc::server {
namespace {

std::string format(const spdlog::details::log_msg& msg) {
    spdlog::memory_buf_t buffer;
    make_json_log_formatter()->format(msg, buffer);
    return {buffer.data(), buffer.size()};
}

TEST(JsonLog, OneObjectALineWithTimeLevelLoggerMessage) {
    // 2026-11-23T12:34:56.789Z
    const auto time =
        std::chrono::system_clock::time_point(std::chrono::milliseconds(1795437296789));
    const std::string payload = "map 'a\"b\\c'\nsecond line\twith a tab and a bad byte \xff";
    const spdlog::details::log_msg msg(time, spdlog::source_loc{}, "server", spdlog::level::warn,
                                       payload);
    const std::string line = format(msg);

    ASSERT_FALSE(line.empty());
    EXPECT_EQ(line.back(), '\n');
    EXPECT_EQ(line.find('\n'), line.size() - 1) << line; // one line, whatever the message
    const auto json = nlohmann::ordered_json::parse(line);
    ASSERT_TRUE(json.is_object()) << line;
    std::vector<std::string> keys;
    for (const auto& [key, value] : json.items()) {
        keys.push_back(key);
    }
    EXPECT_EQ(keys, (std::vector<std::string>{"time", "level", "logger", "msg"}));
    EXPECT_EQ(json["time"], "2026-11-23T12:34:56.789Z");
    EXPECT_EQ(json["level"], "warning");
    EXPECT_EQ(json["logger"], "server");
    EXPECT_EQ(json["msg"], "map 'a\"b\\c'\nsecond line\twith a tab and a bad byte \xEF\xBF\xBD");
}

TEST(JsonLog, LevelsByName) {
    const auto level_of = [](spdlog::level::level_enum level) {
        const spdlog::details::log_msg msg("server", level, "x");
        return nlohmann::json::parse(format(msg))["level"].get<std::string>();
    };
    EXPECT_EQ(level_of(spdlog::level::trace), "trace");
    EXPECT_EQ(level_of(spdlog::level::debug), "debug");
    EXPECT_EQ(level_of(spdlog::level::info), "info");
    EXPECT_EQ(level_of(spdlog::level::err), "error");
    EXPECT_EQ(level_of(spdlog::level::critical), "critical");
}

} // namespace
} // namespace dsoc::server
