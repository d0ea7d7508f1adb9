#pragma once
// The scenario file (TOML): stages, groups and thresholds (docs/simclient.md,
// "Scenario file").

#include "dsoc/simclient/scenario.hpp"

#include <string>
#include <string_view>

namespace dsoc::simclient {

/// Parses scenario TOML `text`; `source` names it in errors. Returns false with `error`
/// ("<source>:<line>:<column>: <key>: <why>") on a syntax error, an unknown key, a value
/// of the wrong type or out of range, an unknown behaviour or a bad threshold.
[[nodiscard]] bool parse_scenario(std::string_view text, std::string_view source, Scenario& out,
                                  std::string& error);

/// Reads and parses the file at `path`; false with `error` also when it cannot be read.
[[nodiscard]] bool load_scenario_file(const std::string& path, Scenario& out, std::string& error);

} // namespace dsoc::simclient
