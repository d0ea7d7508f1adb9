#include "dsoc/server/config_fields.hpp"
#include "dsoc/server/config_file.hpp"
#include "dsoc/server/dsoc_settings.hpp"

#include "support/aggregate_field_count.hpp"

#include <gtest/gtest.h>

#include <type_traits>

namespace dsoc::server {
namespace {

using dsoc::testing::aggregate_field_count;

TEST(ConfigFile, TheFieldListCoversEveryServerConfigField) {
    std::size_t visited = 0;
    ServerConfig c;
    visit_config_fields(c, [&](const char*, auto&) { ++visited; });
    EXPECT_EQ(visited, aggregate_field_count<ServerConfig>())
        << "a ServerConfig field is missing from visit_config_fields (config_fields.hpp)";
}

/// Every field changed from its default, so that a round trip proves each one.
ServerConfig all_changed() {
    ServerConfig c;
    visit_config_fields(c, [](const char*, auto& field) {
        using T = std::decay_t<decltype(field)>;
        if constexpr (std::is_same_v<T, std::vector<DsocSetting>>) {
            field.push_back({"full_test_interval", "7", "test"});
            field.push_back({"tbv_merge_distance", "80.5", "test"});
        } else if constexpr (std::is_same_v<T, std::string>) {
            field += "-x";
        } else if constexpr (interest::NamedChoice<T>) {
            field = interest::names_of(field).back().value; // each default is the first
        } else if constexpr (std::is_same_v<T, bool>) {
            field = !field;
        } else if constexpr (std::is_floating_point_v<T>) {
            field = field * T(2) + T(0.25);
        } else {
            field = static_cast<T>(field + 3);
        }
    });
    return c;
}

TEST(ConfigFile, PrintedConfigReadsBackToTheSameValues) {
    const ServerConfig changed = all_changed();
    const std::string text = format_config_toml(changed);
    ServerConfig read;
    const auto problems = apply_config_toml(text, "printed", read);
    ASSERT_TRUE(problems.empty()) << problems.front() << "\n" << text;
    std::size_t compared = 0;
    visit_config_fields(read, [&](const char* name, const auto& field) {
        visit_config_fields(changed, [&](const char* other, const auto& expected) {
            using T = std::decay_t<decltype(field)>;
            if constexpr (std::is_same_v<T, std::vector<DsocSetting>>) {
                if constexpr (std::is_same_v<decltype(field), decltype(expected)>) {
                    ASSERT_EQ(std::string_view(name), other);
                    // Where each entry came from differs (the printed text's lines).
                    ASSERT_EQ(field.size(), expected.size());
                    for (std::size_t i = 0; i < field.size(); ++i) {
                        EXPECT_EQ(field[i].key, expected[i].key);
                        EXPECT_EQ(field[i].value, expected[i].value);
                        EXPECT_EQ(field[i].origin.rfind("printed:", 0), 0u) << field[i].origin;
                    }
                    ++compared;
                }
            } else if constexpr (std::is_same_v<decltype(field), decltype(expected)>) {
                if (std::string_view(name) == other) {
                    EXPECT_EQ(field, expected) << name;
                    ++compared;
                }
            }
        });
    });
    EXPECT_EQ(compared, aggregate_field_count<ServerConfig>());
}

// `dsoc-server --print-config > server.toml` is the documented first step: the defaults
// must print, read back, and start the server after one edit, the token key file.
TEST(ConfigFile, TheDefaultsNeedOneEditTheTokenKeyFile) {
    const ServerConfig defaults;
    const auto problems = validate(defaults);
    ASSERT_EQ(problems.size(), 1u)
        << "a default that does not start the server: " << problems.back();
    EXPECT_EQ(problems[0].rfind("token_key_file: required unless insecure = true", 0), 0u)
        << problems[0];
    std::string text = format_config_toml(defaults, problems);
    // Listed at the top, as comments.
    EXPECT_NE(text.find("\n# The server refuses to start with these settings until this is "
                        "fixed:\n#   token_key_file: required"),
              std::string::npos)
        << text;
    ServerConfig read;
    ASSERT_TRUE(apply_config_toml(text, "server.toml", read).empty()) << text;
    EXPECT_EQ(validate(read), problems);

    const std::string unset = "\ntoken_key_file = ''\n";
    const auto at = text.find(unset);
    ASSERT_NE(at, std::string::npos) << text;
    text.replace(at, unset.size(), "\ntoken_key_file = '/etc/dsoc/token.key'\n");
    ServerConfig edited;
    ASSERT_TRUE(apply_config_toml(text, "server.toml", edited).empty()) << text;
    EXPECT_TRUE(validate(edited).empty()) << validate(edited).front();
    EXPECT_EQ(format_config_toml(edited).find("# The server refuses"), std::string::npos);
}

TEST(ConfigFile, KeysAbsentFromTheFileKeepTheirValues) {
    ServerConfig c;
    c.bots = 7;
    ASSERT_TRUE(apply_config_toml("tick_rate = 60\npolicy = \"pvs\"\n", "t.toml", c).empty());
    EXPECT_EQ(c.tick_rate, 60);
    EXPECT_EQ(c.policy, interest::PolicyKind::pvs);
    EXPECT_EQ(c.bots, 7);
}

TEST(ConfigFile, ChoicesAreReadByNameAndAWrongNameListsTheAllowedOnes) {
    ServerConfig c;
    ASSERT_TRUE(apply_config_toml("culler = \"both\"\n", "server.toml", c).empty());
    EXPECT_EQ(c.culler, interest::CullerKind::both);
    using Problems = std::vector<std::string>;
    EXPECT_EQ(apply_config_toml("policy = \"psychic\"\n", "server.toml", c),
              Problems{"server.toml:1:10: policy: must be one of dsoc, occlusion, pvs, distance, "
                       "broadcast; got 'psychic'"});
    EXPECT_EQ(apply_config_toml("exact_stages = true\n", "server.toml", c),
              Problems{"server.toml:1:16: exact_stages: expected one of auto, true, false (a "
                       "string), got a boolean"});
    EXPECT_EQ(c.policy, ServerConfig{}.policy);
    // Printed by the same names.
    const std::string text = format_config_toml(c);
    for (const char* line :
         {"\npolicy = 'dsoc'\n", "\nculler = 'both'\n", "\nexact_stages = 'auto'\n"}) {
        EXPECT_NE(text.find(line), std::string::npos) << line << text;
    }
}

TEST(ConfigFile, ProblemsNameTheFileLineFieldAndReason) {
    ServerConfig c;
    const auto problems = apply_config_toml("tick_rate = \"fast\"\n"
                                            "tick_rat = 30\n"
                                            "port = 70000\n"
                                            "max_speed = 250\n",
                                            "server.toml", c);
    ASSERT_EQ(problems.size(), 3u);
    // In field order (port before tick_rate), then unknown keys.
    EXPECT_EQ(problems[0], "server.toml:3:8: port: 70000 does not fit: must be 0..65535");
    EXPECT_EQ(problems[1], "server.toml:1:13: tick_rate: expected an integer, got a string");
    EXPECT_EQ(problems[2].rfind("server.toml:2:1: tick_rat: unknown setting", 0), 0u)
        << problems[2];
    EXPECT_FLOAT_EQ(c.max_speed, 250.0f); // an integer is fine for a float field
    EXPECT_EQ(c.tick_rate, ServerConfig{}.tick_rate);
}

TEST(ConfigFile, SyntaxErrorsSayWhere) {
    ServerConfig c;
    const auto problems = apply_config_toml("bots = 3\nmap = \"oa_dm4\n", "bad.toml", c);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].rfind("bad.toml:2:", 0), 0u) << problems[0];
}

TEST(ConfigFile, NegativeValueForAnUnsignedFieldIsRefused) {
    ServerConfig c;
    const auto problems = apply_config_toml("seed = -1\n", "s.toml", c);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_NE(problems[0].find("seed: -1 does not fit"), std::string::npos) << problems[0];
}

TEST(ConfigFile, UnreadableFileNamesThePath) {
    ServerConfig c;
    const auto problems = apply_config_file("/nonexistent/dsoc.toml", c);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_NE(problems[0].find("/nonexistent/dsoc.toml"), std::string::npos);
}

} // namespace
} // namespace dsoc::server
