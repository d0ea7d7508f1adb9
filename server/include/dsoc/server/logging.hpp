#pragma once
// dsoc-server's log: spdlog's default logger "server" on stderr, as text for people or
// as JSON lines for log collectors (ServerConfig::log_format).

#include "dsoc/server/server_config.hpp"

#include <spdlog/formatter.h>

#include <memory>

namespace dsoc::server {

/// Makes the default logger write to stderr at config.log_level, in config.log_format:
/// "text", "[12:00:00.123] [server] [info] message" (coloured on a terminal), or "json",
/// one object a line as make_json_log_formatter() writes it. The config must have
/// passed validate().
void set_up_logging(const ServerConfig& config);

/// One JSON object a line, keys in this order:
///   {"time":"2026-11-23T12:00:00.123Z","level":"info","logger":"server","msg":"..."}
/// time in UTC with milliseconds; level one of trace, debug, info, warning, error,
/// critical; msg the message as text (bytes that are not UTF-8 become U+FFFD).
[[nodiscard]] std::unique_ptr<spdlog::formatter> make_json_log_formatter();

} // namespace dsoc::server
