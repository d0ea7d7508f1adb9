#include "dsoc/server/logging.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <ctime>

namespace dsoc::server {

namespace {

class JsonLogFormatter final : public spdlog::formatter {
public:
    void format(const spdlog::details::log_msg& msg, spdlog::memory_buf_t& dest) override {
        const auto since_epoch = msg.time.time_since_epoch();
        const std::time_t seconds =
            std::chrono::duration_cast<std::chrono::seconds>(since_epoch).count();
        const auto millis =
            std::chrono::duration_cast<std::chrono::milliseconds>(since_epoch).count() % 1000;
        std::tm utc{};
        ::gmtime_r(&seconds, &utc);
        // ordered_json keeps the documented key order.
        nlohmann::ordered_json line;
        line["time"] =
            fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z", utc.tm_year + 1900,
                        utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, millis);
        const auto level = spdlog::level::to_string_view(msg.level);
        line["level"] = std::string(level.data(), level.size());
        line["logger"] = std::string(msg.logger_name.data(), msg.logger_name.size());
        line["msg"] = std::string(msg.payload.data(), msg.payload.size());
        const std::string text =
            line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
        dest.append(text.data(), text.data() + text.size());
        dest.push_back('\n');
    }

    [[nodiscard]] std::unique_ptr<spdlog::formatter> clone() const override {
        return std::make_unique<JsonLogFormatter>();
    }
};

} // namespace

std::unique_ptr<spdlog::formatter> make_json_log_formatter() {
    return std::make_unique<JsonLogFormatter>();
}

void set_up_logging(const ServerConfig& config) {
    // Not through spdlog's registry: set_default_logger() replaces, so a second call
    // (tests) does not find the name taken.
    std::shared_ptr<spdlog::logger> logger;
    if (config.log_format == "json") {
        logger = std::make_shared<spdlog::logger>(
            "server", std::make_shared<spdlog::sinks::stderr_sink_mt>());
        logger->set_formatter(make_json_log_formatter());
    } else {
        logger = std::make_shared<spdlog::logger>(
            "server", std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
        logger->set_pattern("[%H:%M:%S.%e] [server] [%^%l%$] %v");
    }
    logger->set_level(spdlog::level::from_str(config.log_level));
    spdlog::set_default_logger(std::move(logger));
}

} // namespace dsoc::server
