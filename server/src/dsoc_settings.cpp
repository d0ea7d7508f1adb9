#include "dsoc/server/dsoc_settings.hpp"

#include "dsoc/interest/interest_policy.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <type_traits>

namespace dsoc::server {

namespace {

/// `value` as TOML: shortest round-trip floats (always with a '.' or an exponent, so
/// they read back as floats), quoted strategy names.
template <class T>
std::string toml_value(T value) {
    if constexpr (std::is_same_v<T, bool>) {
        return value ? "true" : "false";
    } else if constexpr (std::is_same_v<T, visibility::TbvStrategy>) {
        return std::string("\"") + visibility::to_string(value) + "\"";
    } else if constexpr (std::is_floating_point_v<T>) {
        std::array<char, 64> text{};
        const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
        std::string s(text.data(), ec == std::errc() ? end : text.data());
        if (s.find_first_of(".eEn") == std::string::npos) { // n: inf, nan
            s += ".0";
        }
        return s;
    } else {
        return std::to_string(value);
    }
}

bool is_flat_field(std::string_view name) {
    return name == "tick_rate" || name == "strategy" || name == "region_reuse_margin";
}

} // namespace

std::string set_dsoc_setting(std::vector<DsocSetting>& settings, std::string_view key,
                             std::string_view value, std::string_view origin) {
    if (key == "tick_rate") {
        return "not a [dsoc] field: DSOCConfig's tick_rate is the server's tick_rate";
    }
    visibility::DSOCConfig scratch;
    if (auto why = visibility::set_field(scratch, key, value); !why.empty()) {
        return why;
    }
    const auto same = std::find_if(settings.begin(), settings.end(),
                                   [&](const DsocSetting& s) { return s.key == key; });
    if (same != settings.end()) {
        settings.erase(same); // the later source wins; it goes last
    }
    settings.push_back({std::string(key), std::string(value), std::string(origin)});
    return {};
}

std::string set_dsoc_setting_from_flag(std::vector<DsocSetting>& settings,
                                       std::string_view key_value) {
    const auto equals = key_value.find('=');
    if (equals == std::string_view::npos || equals == 0) {
        return "--dsoc '" + std::string(key_value) + "': expected KEY=VALUE (a DSOCConfig field)";
    }
    const std::string why = set_dsoc_setting(settings, key_value.substr(0, equals),
                                             key_value.substr(equals + 1), "--dsoc");
    return why.empty() ? why : "--dsoc '" + std::string(key_value) + "': " + why;
}

visibility::DSOCConfig dsoc_config(const ServerConfig& config) {
    visibility::DSOCConfig dsoc;
    [[maybe_unused]] const bool known =
        visibility::parse_tbv_strategy(config.tbv_strategy, dsoc.strategy); // validated
    dsoc.region_reuse_margin = config.region_reuse_margin;
    interest::apply_policy_presets(config.policy, dsoc);
    for (const DsocSetting& s : config.dsoc) {
        [[maybe_unused]] const auto why = visibility::set_field(dsoc, s.key, s.value);
    }
    dsoc.tick_rate = config.tick_rate; // the one rate; set_dsoc_setting() refuses another
    return dsoc;
}

std::vector<std::string> validate_dsoc_settings(const ServerConfig& config) {
    std::vector<std::string> problems;
    const auto entry = [&](std::string_view field) -> const DsocSetting* {
        for (const DsocSetting& s : config.dsoc) {
            if (s.key == field) {
                return &s;
            }
        }
        return nullptr;
    };
    for (const DsocSetting& s : config.dsoc) {
        std::vector<DsocSetting> scratch;
        if (auto why = set_dsoc_setting(scratch, s.key, s.value, s.origin); !why.empty()) {
            problems.push_back(s.origin + ": dsoc." + s.key + ": " + why);
        }
    }
    const visibility::DSOCConfig dsoc = dsoc_config(config);
    for (const std::string& problem : visibility::validate(dsoc)) {
        const std::string field = problem.substr(0, problem.find(':'));
        if (const DsocSetting* s = entry(field)) {
            problems.push_back(s->origin + ": dsoc." + problem + " (got " + s->value + ")");
        } else if (!is_flat_field(field)) { // a flat key's own check names it already
            problems.push_back("dsoc." + problem);
        }
    }
    return problems;
}

std::string format_dsoc_table(const ServerConfig& config) {
    std::string out =
        "\n[dsoc]\n"
        "# The dsoc and occlusion policies' culler and TBV settings (visibility::DSOCConfig,\n"
        "# docs/operations.md). A line set here overrides tbv_strategy,\n"
        "# region_reuse_margin and the occlusion policy's presets; commented lines show\n"
        "# the value in effect. Its tick_rate is always the server's.\n";
    const visibility::DSOCConfig dsoc = dsoc_config(config);
    visit_dsoc_fields(dsoc, [&](const char* name, auto value) {
        const bool set = std::any_of(config.dsoc.begin(), config.dsoc.end(),
                                     [&](const DsocSetting& s) { return s.key == name; });
        out += std::string(set ? "" : "# ") + name + " = " + toml_value(value) + "\n";
    });
    return out;
}

} // namespace dsoc::server
