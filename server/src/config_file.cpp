#include "dsoc/server/config_file.hpp"

#include "dsoc/common/read_file.hpp"
#include "dsoc/interest/policy_choices.hpp"

#include "dsoc/server/config_fields.hpp"
#include "dsoc/server/dsoc_settings.hpp"

#include <toml++/toml.h>

#include <array>
#include <charconv>
#include <limits>
#include <set>
#include <sstream>
#include <type_traits>

namespace dsoc::server {

namespace {

std::string where(std::string_view source, const toml::source_region& region) {
    return std::string(source) + ":" + std::to_string(region.begin.line) + ":" +
           std::to_string(region.begin.column);
}

const char* type_name(toml::node_type type) {
    switch (type) {
    case toml::node_type::string:
        return "a string";
    case toml::node_type::integer:
        return "an integer";
    case toml::node_type::floating_point:
        return "a number";
    case toml::node_type::boolean:
        return "a boolean";
    case toml::node_type::table:
        return "a table";
    case toml::node_type::array:
        return "an array";
    default:
        return "a date or time";
    }
}

/// Reads `node` into `field`; returns why not, or an empty string.
template <class T>
std::string read_value(const toml::node& node, T& field) {
    if constexpr (std::is_same_v<T, std::string>) {
        if (const auto* s = node.as_string()) {
            field = s->get();
            return {};
        }
        return std::string("expected a string, got ") + type_name(node.type());
    } else if constexpr (interest::NamedChoice<T>) {
        const auto* s = node.as_string();
        if (s == nullptr) {
            return "expected one of " + interest::choice_names<T>() + " (a string), got " +
                   type_name(node.type());
        }
        const auto choice = interest::parse_choice<T>(s->get());
        if (!choice) {
            return interest::not_a_choice<T>(s->get());
        }
        field = *choice;
        return {};
    } else if constexpr (std::is_same_v<T, bool>) {
        if (const auto* b = node.as_boolean()) {
            field = b->get();
            return {};
        }
        return std::string("expected true or false, got ") + type_name(node.type());
    } else if constexpr (std::is_floating_point_v<T>) {
        if (const auto* f = node.as_floating_point()) {
            field = static_cast<T>(f->get());
            return {};
        }
        if (const auto* i = node.as_integer()) {
            field = static_cast<T>(i->get());
            return {};
        }
        return std::string("expected a number, got ") + type_name(node.type());
    } else {
        static_assert(std::is_integral_v<T>);
        const auto* i = node.as_integer();
        if (i == nullptr) {
            return std::string("expected an integer, got ") + type_name(node.type());
        }
        const std::int64_t v = i->get();
        const bool fits =
            std::is_signed_v<T>
                ? v >= static_cast<std::int64_t>(std::numeric_limits<T>::min()) &&
                      v <= static_cast<std::int64_t>(std::numeric_limits<T>::max())
                : v >= 0 && static_cast<std::uint64_t>(v) <=
                                static_cast<std::uint64_t>(std::numeric_limits<T>::max());
        if (!fits) {
            return std::to_string(v) + " does not fit: must be " +
                   std::to_string(std::numeric_limits<T>::min()) + ".." +
                   std::to_string(std::numeric_limits<T>::max());
        }
        field = static_cast<T>(v);
        return {};
    }
}

/// A [dsoc] value as the text DSOCConfig's set_field() reads, if `node` has the type of
/// a field holding T; returns why not, or an empty string.
template <class T>
std::string dsoc_value_text(const toml::node& node, std::string& text) {
    if constexpr (std::is_same_v<T, bool>) {
        if (const auto* b = node.as_boolean()) {
            text = b->get() ? "true" : "false";
            return {};
        }
        return std::string("expected true or false, got ") + type_name(node.type());
    } else if constexpr (std::is_same_v<T, visibility::TbvStrategy>) {
        if (const auto* s = node.as_string()) {
            text = s->get();
            return {};
        }
        return std::string("expected \"explicit\", \"adaptive\" or \"fuzzy\", got ") +
               type_name(node.type());
    } else if constexpr (std::is_floating_point_v<T>) {
        if (const auto* i = node.as_integer()) {
            text = std::to_string(i->get());
            return {};
        }
        if (const auto* f = node.as_floating_point()) {
            std::array<char, 64> chars{};
            const auto [end, ec] =
                std::to_chars(chars.data(), chars.data() + chars.size(), f->get());
            text.assign(chars.data(), ec == std::errc() ? end : chars.data());
            return {};
        }
        return std::string("expected a number, got ") + type_name(node.type());
    } else {
        static_assert(std::is_integral_v<T>);
        if (const auto* i = node.as_integer()) {
            text = std::to_string(i->get()); // set_field() refuses what does not fit
            return {};
        }
        return std::string("expected an integer, got ") + type_name(node.type());
    }
}

/// The [dsoc] table into `settings`; each problem names the place, the field and why.
void read_dsoc_table(const toml::node& node, std::string_view source,
                     std::vector<DsocSetting>& settings, std::vector<std::string>& problems) {
    const auto* table = node.as_table();
    if (table == nullptr) {
        problems.push_back(where(source, node.source()) +
                           ": dsoc: expected a table ([dsoc]), got " + type_name(node.type()));
        return;
    }
    for (const auto& entry : *table) {
        // Named references, not a structured binding: clang 14 (Debian 12's, used for
        // the fuzz targets) rejects a lambda capturing a structured binding.
        const toml::key& key = entry.first;
        const toml::node& value = entry.second;
        const std::string name(key.str());
        const std::string at = where(source, value.source());
        // tick_rate: set_dsoc_setting() says whose it is.
        std::string why = name == "tick_rate"
                              ? set_dsoc_setting(settings, name, {}, at)
                              : "unknown setting: not a visibility::DSOCConfig field (see "
                                "dsoc-server --print-config)";
        std::string text;
        visit_dsoc_fields(visibility::DSOCConfig{}, [&](const char* field, auto field_value) {
            if (name == field) {
                why = dsoc_value_text<decltype(field_value)>(value, text);
            }
        });
        if (why.empty()) {
            why = set_dsoc_setting(settings, name, text, at);
        }
        if (!why.empty()) {
            problems.push_back(at + ": dsoc." + name + ": " + why);
        }
    }
}

} // namespace

std::vector<std::string> apply_config_toml(std::string_view text, std::string_view source,
                                           ServerConfig& config) {
    std::vector<std::string> problems;
    toml::table table;
    try {
        table = toml::parse(text, source);
    } catch (const toml::parse_error& e) {
        problems.push_back(where(source, e.source()) + ": " + std::string(e.description()));
        return problems;
    }
    std::set<std::string, std::less<>> known;
    visit_config_fields(config, [&](const char* name, auto& field) {
        known.insert(name);
        const toml::node* node = table.get(name);
        if (node == nullptr) {
            return;
        }
        if constexpr (std::is_same_v<std::decay_t<decltype(field)>, std::vector<DsocSetting>>) {
            read_dsoc_table(*node, source, field, problems);
        } else if (auto why = read_value(*node, field); !why.empty()) {
            problems.push_back(where(source, node->source()) + ": " + name + ": " + why);
        }
    });
    for (const auto& [key, node] : table) {
        if (known.find(key.str()) == known.end()) {
            problems.push_back(where(source, key.source()) + ": " + std::string(key.str()) +
                               ": unknown setting (see dsoc-server --print-config)");
        }
    }
    return problems;
}

std::vector<std::string> apply_config_file(const std::string& path, ServerConfig& config) {
    std::string text;
    if (const std::string why = common::read_file(path, text); !why.empty()) {
        return {path + ": cannot read config file: " + why};
    }
    return apply_config_toml(text, path, config);
}

std::string format_config_toml(const ServerConfig& config,
                               const std::vector<std::string>& problems) {
    std::ostringstream out;
    out << "# dsoc-server settings (TOML); every key is optional.\n";
    if (!problems.empty()) {
        out << "# The server refuses to start with these settings until this is fixed:\n";
        for (const auto& problem : problems) {
            out << "#   " << problem << "\n";
        }
    }
    visit_config_fields(config, [&](const char* name, const auto& field) {
        using T = std::decay_t<decltype(field)>;
        toml::table line; // one key per table keeps the declaration order
        if constexpr (std::is_same_v<T, std::vector<DsocSetting>>) {
            return; // a table: after every flat key (below)
        } else if constexpr (std::is_same_v<T, std::string> || std::is_same_v<T, bool>) {
            line.insert(name, field);
        } else if constexpr (interest::NamedChoice<T>) {
            line.insert(name, std::string(interest::name_of(field)));
        } else if constexpr (std::is_floating_point_v<T>) {
            line.insert(name, static_cast<double>(field));
        } else {
            // validate() keeps unsigned fields within int64 (TOML's integer range).
            line.insert(name, static_cast<std::int64_t>(field));
        }
        out << line << "\n";
    });
    out << format_dsoc_table(config);
    return out.str();
}

} // namespace dsoc::server
