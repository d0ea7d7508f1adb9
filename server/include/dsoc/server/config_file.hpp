#pragma once
// ServerConfig <-> TOML (toml++). One key per ServerConfig field, named as in the
// struct (see config_fields.hpp), and a [dsoc] table holding any field of
// visibility::DSOCConfig by its name (dsoc_settings.hpp says which value wins), e.g.
//
//   tick_rate = 30
//   policy = "dsoc"
//   token_key_file = "/etc/dsoc/token.key"
//
//   [dsoc]
//   full_test_interval = 2
//
// Keys absent from the file keep the value already in the config, so a file can
// hold only what differs from the defaults; command-line flags are applied after
// the file and override it.

#include "dsoc/server/server_config.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace dsoc::server {

/// Applies the settings in TOML `text` to `config`. Returns every problem, each as
/// "<source>:<line>:<column>: <field>: <why>" (a syntax error, an unknown key, a
/// value of the wrong type or out of the field's type range); empty on success.
/// On problems, the fields that did read cleanly are applied and the rest are left
/// alone. Range checks beyond the type are validate()'s job.
[[nodiscard]] std::vector<std::string>
apply_config_toml(std::string_view text, std::string_view source, ServerConfig& config);

/// Reads the file at `path` and applies it as apply_config_toml() does; an unreadable
/// file is one problem naming the path and the OS error.
[[nodiscard]] std::vector<std::string> apply_config_file(const std::string& path,
                                                         ServerConfig& config);

/// Every field of `config` as TOML, one line each in declaration order; apply_config_toml() reads
/// it back to an equal config. `problems` (validate()'s, say) are listed in comments at the
/// top: what must change before the server starts with these settings.
[[nodiscard]] std::string format_config_toml(const ServerConfig& config,
                                             const std::vector<std::string>& problems = {});

} // namespace dsoc::server
