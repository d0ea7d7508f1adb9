#pragma once
// The server's [dsoc] settings: any field of visibility::DSOCConfig (the culler and
// TBV settings of the dsoc and occlusion policies), named as in that struct, from the
// config file's [dsoc] table or from `--dsoc KEY=VALUE`:
//
//   [dsoc]
//   full_test_interval = 2
//   tbv_merge_distance = 96.0
//   strategy = "explicit"
//
// Which wins: a [dsoc] entry overrides everything else that sets the same field - the
// flat keys tick_rate, tbv_strategy and region_reuse_margin, and the occlusion
// policy's presets (no TBVs, no buffer reuse, full test every tick, no blocker hints).
// Among [dsoc] entries the later source wins: `--dsoc` flags over the file. Other
// policies ignore the table (its values are still validated).

#include "dsoc/server/server_config.hpp"
#include "dsoc/visibility/dsoc_config.hpp"

#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace dsoc::server {

/// Calls `visit(name, value)` for every field of `config` (a visibility::DSOCConfig),
/// in the order of dsoc_config.hpp, with the name DSOCConfig's set_field() takes.
/// `value` is int, float, bool or visibility::TbvStrategy. A test fails when a field
/// is missing.
template <class Config, class Visitor>
void visit_dsoc_fields(const Config& config, Visitor&& visit) {
    static_assert(std::is_same_v<Config, visibility::DSOCConfig>);
    visit("tick_rate", config.tick_rate);
    visit("strategy", config.strategy);
    visit("default_tbv_duration", config.default_tbv_duration);
    visit("tbv_expansion_factor", config.tbv_expansion_factor);
    visit("max_tbvs_per_object", config.max_tbvs_per_object);
    visit("max_tbvs_per_client", config.max_tbvs_per_client);
    visit("velocity_threshold", config.velocity_threshold);
    visit("min_adaptive_duration", config.min_adaptive_duration);
    visit("max_adaptive_duration", config.max_adaptive_duration);
    visit("fuzzy_confidence", config.fuzzy_confidence);
    visit("tbv_merge_distance", config.tbv_merge_distance);
    visit("region_reuse_margin", config.region_reuse_margin);
    visit("lod_near_distance", config.lod_near_distance);
    visit("lod_far_distance", config.lod_far_distance);
    visit("entity_cluster_size", config.entity_cluster_size);
    visit("tbvs_enabled", config.tbvs_enabled);
    visit("reuse_buffers", config.reuse_buffers);
    visit("exact_region_tests", config.exact_region_tests);
    visit("blocker_hints", config.blocker_hints);
    visit("full_test_interval", config.full_test_interval);
    visit("validate_state", config.validate_state);
}

/// Adds `key = value` to `settings`, replacing an earlier entry for the same key (the
/// later source wins). `value` is text as DSOCConfig's set_field() reads it (numbers,
/// true/false/1/0, explicit/adaptive/fuzzy); `origin` says where it came from
/// ("server.toml:12:1", "--dsoc"). Returns "" on success, else why not (an unknown
/// field or a value that does not parse), and `settings` is unchanged. Ranges are
/// checked by validate().
[[nodiscard]] std::string set_dsoc_setting(std::vector<DsocSetting>& settings, std::string_view key,
                                           std::string_view value, std::string_view origin);

/// The same from `--dsoc KEY=VALUE` text (split at the first '='); origin "--dsoc".
/// Returns "" on success, else "--dsoc '<text>': <why>".
[[nodiscard]] std::string set_dsoc_setting_from_flag(std::vector<DsocSetting>& settings,
                                                     std::string_view key_value);

/// The DSOCConfig `config` describes: defaults, then the flat keys (tick_rate,
/// tbv_strategy, region_reuse_margin), then the occlusion policy's presets when
/// config.policy is "occlusion", then config.dsoc's entries in order.
[[nodiscard]] visibility::DSOCConfig dsoc_config(const ServerConfig& config);

/// Problems with config.dsoc, each "<origin>: dsoc.<field>: <why>": entries that do
/// not parse, a tick_rate that differs from the server's, and whatever
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
