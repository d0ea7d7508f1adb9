#pragma once
// The server's [dsoc] settings: any field of visibility::DSOCConfig (the culler and
// TBV settings of the dsoc and occlusion policies), named as in that struct, from the
// config file's [dsoc] table or from `--dsoc KEY=VALUE`:
//
//   [dsoc]
//   full_test_interval = 2
//   tbvs_enabled = true
//   strategy = "explicit"
//
// Which wins: a [dsoc] entry overrides everything else that sets the same field - the
// flat keys tbv_strategy and region_reuse_margin, and the occlusion
// policy's presets (no TBVs, no buffer reuse, full test every tick, no blocker hints).
// Among [dsoc] entries the later source wins: `--dsoc` flags over the file. Other
// policies ignore the table (its values are still validated). DSOCConfig's tick_rate
// is not in the table: it is always the server's tick_rate.

#include "dsoc/server/server_config.hpp"
#include "dsoc/visibility/dsoc_config.hpp"

#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace dsoc::server {

/// The [dsoc] table's fields: visibility::visit_fields() but tick_rate, which the server
/// sets from its own tick_rate (dsoc_config()), so the rate is written in one place.
/// `value` is int, float, bool or visibility::TbvStrategy.
template <class Visitor>
void visit_dsoc_fields(const visibility::DSOCConfig& config, Visitor&& visit) {
    visibility::visit_fields(config, [&](std::string_view name, const auto& value) {
        if (name != "tick_rate") {
            visit(name.data(), value);
        }
    });
}

/// Adds `key = value` to `settings`, replacing an earlier entry for the same key (the
/// later source wins). `value` is text as DSOCConfig's set_field() reads it (numbers,
/// true/false/1/0, explicit/adaptive/fuzzy); `origin` says where it came from
/// ("server.toml:12:1", "--dsoc"). Returns "" on success, else why not (an unknown
/// field, tick_rate, or a value that does not parse), and `settings` is unchanged. Ranges are
/// checked by validate().
[[nodiscard]] std::string set_dsoc_setting(std::vector<DsocSetting>& settings, std::string_view key,
                                           std::string_view value, std::string_view origin);

/// The same from `--dsoc KEY=VALUE` text (split at the first '='); origin "--dsoc".
/// Returns "" on success, else "--dsoc '<text>': <why>".
[[nodiscard]] std::string set_dsoc_setting_from_flag(std::vector<DsocSetting>& settings,
                                                     std::string_view key_value);

/// The DSOCConfig `config` describes: defaults, then the flat keys (tbv_strategy,
/// region_reuse_margin), then the occlusion policy's presets when config.policy is
/// "occlusion", then config.dsoc's entries in order; tick_rate is config.tick_rate.
[[nodiscard]] visibility::DSOCConfig dsoc_config(const ServerConfig& config);

/// Problems with config.dsoc, each "<origin>: dsoc.<field>: <why>": entries that do
/// not parse, and whatever
/// visibility::validate() finds in dsoc_config(config) (a problem in a field no entry
/// sets comes from a flat key, which validate(ServerConfig) reports itself, or from a
/// preset, and is reported without origin). Empty when usable.
[[nodiscard]] std::vector<std::string> validate_dsoc_settings(const ServerConfig& config);

/// The [dsoc] table for --print-config: a header comment, then every DSOCConfig field
/// with the value in effect (dsoc_config(config)), as a live line when config.dsoc sets
/// it and as a comment otherwise, so that reading the text back gives the same
/// entries and printing again gives the same text. Floats are written shortest
/// round-trip (std::to_chars).
[[nodiscard]] std::string format_dsoc_table(const ServerConfig& config);

} // namespace dsoc::server
