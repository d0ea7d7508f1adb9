// The [dsoc] table: every visibility::DSOCConfig field by name from the config file
// or --dsoc, what wins over the flat keys and presets, errors naming the place, the
// field and why, and --print-config listing every field.

#include "dsoc/server/config_file.hpp"
#include "dsoc/server/dsoc_settings.hpp"

#include "support/aggregate_field_count.hpp"

#include <gtest/gtest.h>

#include <map>
#include <sstream>
#include <string>
#include <type_traits>
#include <variant>

namespace dsoc::server {
namespace {

using dsoc::testing::aggregate_field_count;

using FieldValue = std::variant<int, float, bool, visibility::TbvStrategy>;

std::map<std::string, FieldValue> fields_of(const visibility::DSOCConfig& c) {
    std::map<std::string, FieldValue> out;
    visibility::visit_fields(c, [&](const char* name, auto value) { out[name] = value; });
    return out;
}

ServerConfig insecure() {
    ServerConfig c;
    c.insecure = true;
    return c;
}

TEST(DsocSettings, EveryDsocConfigFieldIsListedAndSetsItsOwnMember) {
    const auto defaults = fields_of(visibility::DSOCConfig{});
    EXPECT_EQ(defaults.size(), aggregate_field_count<visibility::DSOCConfig>())
        << "a DSOCConfig field is missing from visit_fields (dsoc_config.hpp)";
    // Setting each field by name through the server changes that field and no other:
    // the names are set_field()'s and each reads the member it names.
    for (const auto& [name, value] : defaults) {
        if (name == "tick_rate") {
            continue; // the server's own (ServerTickRateIsTheOneRate)
        }
        const std::string changed = std::visit(
            [](auto v) -> std::string {
                using T = decltype(v);
                if constexpr (std::is_same_v<T, bool>) {
                    return v ? "false" : "true";
                } else if constexpr (std::is_same_v<T, visibility::TbvStrategy>) {
                    return v == visibility::TbvStrategy::fuzzy ? "explicit" : "fuzzy";
                } else {
                    return std::to_string(v + 1);
                }
            },
            value);
        ServerConfig c = insecure();
        ASSERT_EQ(set_dsoc_setting(c.dsoc, name, changed, "test"), "") << name;
        const auto now = fields_of(dsoc_config(c));
        for (const auto& [other, v] : now) {
            if (other == name) {
                EXPECT_NE(v, defaults.at(other)) << name << " = " << changed << " changed nothing";
            } else if (other != "region_reuse_margin") {
                EXPECT_EQ(v, defaults.at(other)) << "setting " << name << " changed " << other;
            }
        }
    }
}

TEST(DsocSettings, TableEntriesWinOverFlatKeysAndPresets) {
    ServerConfig c = insecure();
    const auto problems = apply_config_toml("policy = \"occlusion\"\n"
                                            "region_reuse_margin = 24\n"
                                            "tbv_strategy = \"explicit\"\n"
                                            "[dsoc]\n"
                                            "region_reuse_margin = 40\n"
                                            "full_test_interval = 2\n"
                                            "tbv_merge_distance = 96.5\n"
                                            "tbvs_enabled = true\n",
                                            "t.toml", c);
    ASSERT_TRUE(problems.empty()) << problems.front();
    EXPECT_TRUE(validate(c).empty()) << validate(c).front();
    const visibility::DSOCConfig d = dsoc_config(c);
    EXPECT_FLOAT_EQ(d.region_reuse_margin, 40.0f);                     // [dsoc] over the flat key
    EXPECT_EQ(d.strategy, visibility::TbvStrategy::explicit_duration); // flat key, not overridden
    EXPECT_EQ(d.full_test_interval, 2); // over the occlusion preset (1)
    EXPECT_TRUE(d.tbvs_enabled);        // over the occlusion preset
    EXPECT_FALSE(d.reuse_buffers);      // preset, not overridden
    EXPECT_FLOAT_EQ(d.tbv_merge_distance, 96.5f);
    EXPECT_EQ(d.tick_rate, c.tick_rate);
    // The entry says where it was set.
    ASSERT_EQ(c.dsoc.size(), 4u);
    EXPECT_EQ(c.dsoc[0].origin.rfind("t.toml:", 0), 0u) << c.dsoc[0].origin;

    // --dsoc after the file: the flag's value wins and says so.
    ASSERT_EQ(set_dsoc_setting_from_flag(c.dsoc, "full_test_interval=3"), "");
    EXPECT_EQ(dsoc_config(c).full_test_interval, 3);
    ASSERT_EQ(c.dsoc.size(), 4u);
    EXPECT_EQ(c.dsoc.back().origin, "--dsoc");
}

TEST(DsocSettings, BadEntriesNameTheFileLineFieldAndReason) {
    ServerConfig c = insecure();
    const auto problems = apply_config_toml("[dsoc]\n"
                                            "full_test_intervall = 2\n"
                                            "full_test_interval = 2.5\n"
                                            "strategy = \"sideways\"\n"
                                            "blocker_hints = 1\n",
                                            "server.toml", c);
    ASSERT_EQ(problems.size(), 4u);
    // toml++ walks a table in key order.
    EXPECT_EQ(problems[0], "server.toml:5:17: dsoc.blocker_hints: expected true or false, got an "
                           "integer");
    EXPECT_EQ(problems[1], "server.toml:3:22: dsoc.full_test_interval: expected an integer, got "
                           "a number");
    EXPECT_EQ(problems[2].rfind("server.toml:2:23: dsoc.full_test_intervall: unknown setting", 0),
              0u)
        << problems[2];
    EXPECT_EQ(problems[3], "server.toml:4:12: dsoc.strategy: bad value 'sideways' for strategy "
                           "(explicit, adaptive or fuzzy)");
    EXPECT_TRUE(c.dsoc.empty()); // nothing half-applied
}

TEST(DsocSettings, OutOfRangeValuesFailValidationNamingWhereTheyWereSet) {
    ServerConfig c = insecure();
    ASSERT_TRUE(apply_config_toml("tick_rate = 20\n"
                                  "[dsoc]\n"
                                  "full_test_interval = 0\n",
                                  "server.toml", c)
                    .empty());
    ASSERT_EQ(set_dsoc_setting_from_flag(c.dsoc, "fuzzy_confidence=0.2"), "");
    const auto problems = validate(c);
    ASSERT_EQ(problems.size(), 2u) << problems.front();
    // In DSOCConfig's validate() order.
    EXPECT_EQ(problems[0], "--dsoc: dsoc.fuzzy_confidence: must be in [0.5, 0.999] (got 0.2)");
    EXPECT_EQ(problems[1],
              "server.toml:3:22: dsoc.full_test_interval: must be 1..64 ticks (got 0)");

    std::vector<DsocSetting> settings;
    EXPECT_EQ(set_dsoc_setting_from_flag(settings, "full_test_interval"),
              "--dsoc 'full_test_interval': expected KEY=VALUE (a DSOCConfig field)");
    EXPECT_EQ(set_dsoc_setting_from_flag(settings, "no_such=1"),
              "--dsoc 'no_such=1': unknown DSOCConfig field 'no_such'");
    EXPECT_TRUE(settings.empty());
}

TEST(DsocSettings, ServerTickRateIsTheOneRate) {
    // DSOCConfig's tick_rate is the server's: the [dsoc] table has no other.
    ServerConfig c = insecure();
    const auto problems = apply_config_toml("tick_rate = 20\n"
                                            "[dsoc]\n"
                                            "tick_rate = 30\n",
                                            "server.toml", c);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0], "server.toml:3:13: dsoc.tick_rate: not a [dsoc] field: DSOCConfig's "
                           "tick_rate is the server's tick_rate");
    EXPECT_NE(set_dsoc_setting_from_flag(c.dsoc, "tick_rate=30"), "");
    EXPECT_TRUE(c.dsoc.empty());
    c.tick_rate = 20;
    EXPECT_EQ(dsoc_config(c).tick_rate, 20);
}

TEST(DsocSettings, PrintedConfigListsEveryFieldAndReadsBack) {
    ServerConfig c = insecure();
    c.policy = interest::PolicyKind::occlusion;
    ASSERT_EQ(set_dsoc_setting(c.dsoc, "tbv_expansion_factor", "1.35", "test"), "");
    ASSERT_EQ(set_dsoc_setting(c.dsoc, "strategy", "fuzzy", "test"), "");
    const std::string printed = format_config_toml(c);
    const auto table = printed.substr(printed.find("\n[dsoc]\n"));
    std::size_t listed = 0;
    visit_dsoc_fields(visibility::DSOCConfig{}, [&](const char* name, auto) {
        // std::string first: GCC 12 warns falsely (-Wrestrict) on "\n" + std::string.
        const std::string key = std::string(name) + " = ";
        listed += table.find('\n' + key) != std::string::npos ||
                  table.find(std::string("\n# ") + key) != std::string::npos;
    });
    EXPECT_EQ(listed, aggregate_field_count<visibility::DSOCConfig>() - 1) // all but tick_rate
        << table;
    // Set lines are live; the others show the value in effect (here the presets).
    EXPECT_NE(table.find("\ntbv_expansion_factor = 1.35\n"), std::string::npos) << table;
    EXPECT_NE(table.find("\nstrategy = \"fuzzy\"\n"), std::string::npos) << table;
    EXPECT_NE(table.find("\n# tbvs_enabled = false\n"), std::string::npos) << table;
    EXPECT_NE(table.find("\n# full_test_interval = 1\n"), std::string::npos) << table;

    ServerConfig again;
    const auto problems = apply_config_toml(printed, "printed.toml", again);
    ASSERT_TRUE(problems.empty()) << problems.front() << "\n" << printed;
    EXPECT_EQ(format_config_toml(again), printed);
    ASSERT_EQ(again.dsoc.size(), 2u);
    EXPECT_EQ(fields_of(dsoc_config(again)), fields_of(dsoc_config(c)));
}

} // namespace
} // namespace dsoc::server
