// Map sanity checks: each absurd content gives its finding (a warning, or "unusable"
// where no server should run the map), and sound maps give none.

#include "dsoc/maps/generators.hpp"
#include "dsoc/maps/map_checks.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/map_spec.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

namespace dsoc::maps {
namespace {

/// A floor, a solid pillar and a spawn point standing on the floor; `extra` adds lines.
Map text_map(const std::string& extra) {
    const std::string text = "dsoc-map 1\n"
                             "box solid -512 -512 -16 512 512 0\n"
                             "box solid 100 100 0 200 200 128\n" +
                             extra;
    auto spec = parse_text_map(text, "test.dsocmap");
    EXPECT_TRUE(spec.ok()) << spec.error().message();
    return build_map(spec.value(), "test.dsocmap");
}

const MapFinding* find(const std::vector<MapFinding>& findings, const std::string& code) {
    const auto it = std::find_if(findings.begin(), findings.end(),
                                 [&](const MapFinding& f) { return f.code == code; });
    return it == findings.end() ? nullptr : &*it;
}

std::string codes(const std::vector<MapFinding>& findings) {
    std::string out;
    for (const auto& f : findings) {
        out += f.code + " (" + to_string(f.severity) + "): " + f.text + "\n";
    }
    return out;
}

/// Expects the finding `code`, of `severity`, whose text holds every one of `parts`.
void expect_finding(const std::vector<MapFinding>& findings, const std::string& code,
                    FindingSeverity severity, std::initializer_list<const char*> parts) {
    const MapFinding* f = find(findings, code);
    ASSERT_NE(f, nullptr) << code << " missing from:\n" << codes(findings);
    EXPECT_EQ(f->severity, severity) << code;
    for (const char* part : parts) {
        EXPECT_NE(f->text.find(part), std::string::npos) << "'" << part << "' not in " << f->text;
    }
}

TEST(MapChecks, SoundMapsHaveNoFindings) {
    EXPECT_EQ(codes(check_map(text_map("spawn 0 0 25 90\n"))), "");
    EXPECT_EQ(codes(check_map(build_map(generate_rooms({}), "gen:rooms"))), "");
    EXPECT_EQ(codes(check_map(build_map(generate_city({}), "gen:city"))), "");
}

TEST(MapChecks, EveryOpenArenaMapIsSound) {
    DSOC_REQUIRE_OPENARENA();
    const MapSearch search{{test::kOpenArenaPak}};
    for (const std::string& name : list_maps(search)) {
        const auto map = load_map(name, search);
        ASSERT_TRUE(map.ok()) << map.error().message();
        EXPECT_EQ(codes(check_map(map.value())), "") << name;
    }
}

TEST(MapChecks, NoOccludersIsAWarning) {
    // Glass and caulk block players but not sight: the culler has nothing.
    auto spec = parse_text_map("dsoc-map 1\nbox glass -512 -512 -16 512 512 0\n"
                               "box caulk 100 100 0 200 200 128\nspawn 0 0 25\n",
                               "glass.dsocmap");
    ASSERT_TRUE(spec.ok()) << spec.error().message();
    const auto findings = check_map(build_map(spec.value(), "glass.dsocmap"));
    expect_finding(findings, "no_occluders", FindingSeverity::warning,
                   {"occlusion culling hides nothing"});
    EXPECT_FALSE(any_unusable(findings)) << codes(findings);
}

TEST(MapChecks, SpawnsOutsideTheWorldAreWarnedAndAllOutsideIsUnusable) {
    const auto some = check_map(text_map("spawn 0 0 25\nspawn 5000 0 25\nspawn 0 0 -400\n"));
    expect_finding(some, "spawn_outside_world", FindingSeverity::warning,
                   {"2 of 3 spawn points", "#1 at (5000 0 25)"});
    EXPECT_FALSE(any_unusable(some)) << codes(some);

    // A roofless map's spawn above its walls is inside; far above is not.
    EXPECT_EQ(find(check_map(text_map("spawn 0 0 300\n")), "spawn_outside_world"), nullptr);
    const auto all = check_map(text_map("spawn 5000 0 25\nspawn 0 0 5000\n"));
    expect_finding(all, "no_usable_spawn_point", FindingSeverity::unusable, {"no player"});
}

TEST(MapChecks, SpawnsInsideSolidAreWarned) {
    // Inside the pillar, and one just resting on its top face (not inside).
    const auto findings = check_map(text_map("spawn 150 150 64\nspawn 150 150 128.5\n"));
    expect_finding(findings, "spawn_in_solid", FindingSeverity::warning,
                   {"1 of 2 spawn points", "#0 at (150 150 64)"});
    EXPECT_FALSE(any_unusable(findings));
    EXPECT_TRUE(any_unusable(check_map(text_map("spawn 150 150 64\n"))));
}

TEST(MapChecks, SpawnsInsideAHazardAreWarned) {
    const auto findings = check_map(text_map("spawn 0 0 25\nspawn -300 -300 25\n"
                                             "hazard -400 -400 0 -200 -200 64\n"));
    expect_finding(findings, "spawn_in_hazard", FindingSeverity::warning,
                   {"1 of 2 spawn points", "#1 at (-300 -300 25)"});
    EXPECT_FALSE(any_unusable(findings));
}

TEST(MapChecks, NoSpawnPointsIsUnusable) {
    expect_finding(check_map(text_map("")), "no_spawn_points", FindingSeverity::unusable, {});
}

TEST(MapChecks, EmptyWorldWarnsOfEverything) {
    auto spec = parse_text_map("dsoc-map 1\nspawn 0 0 25\n", "empty.dsocmap");
    ASSERT_TRUE(spec.ok());
    const auto findings = check_map(build_map(spec.value(), "empty.dsocmap"));
    for (const char* code : {"no_occluders", "no_collision_brushes", "no_usable_spawn_point"}) {
        EXPECT_NE(find(findings, code), nullptr) << code << "\n" << codes(findings);
    }
}

TEST(MapChecks, NonFiniteGeometryIsUnusable) {
    Map map = text_map("spawn 0 0 25\n");
    map.spawn_points.push_back({{0.0f, std::numeric_limits<float>::quiet_NaN(), 25.0f}});
    auto findings = check_map(map);
    ASSERT_EQ(findings.size(), 1u) << codes(findings);
    EXPECT_EQ(findings[0].code, "non_finite_geometry");
    EXPECT_EQ(findings[0].severity, FindingSeverity::unusable);
    EXPECT_NE(findings[0].text.find("spawn point 1"), std::string::npos) << findings[0].text;

    Map hazard = text_map("spawn 0 0 25\n");
    hazard.hazards.push_back({{{0, 0, 0}, {std::numeric_limits<float>::infinity(), 1, 1}}, "x"});
    findings = check_map(hazard);
    ASSERT_NE(find(findings, "non_finite_geometry"), nullptr) << codes(findings);
    EXPECT_NE(findings[0].text.find("hazard 0"), std::string::npos) << findings[0].text;
}

TEST(MapChecks, BrushesWithNonFinitePlanesAreLeftOutAndWarned) {
    MapSpec spec;
    spec.brushes.push_back(BrushSpec::box(BrushKind::solid, {{-512, -512, -16}, {512, 512, 0}}));
    BrushSpec bad = BrushSpec::box(BrushKind::solid, {{0, 0, 0}, {64, 64, 64}});
    bad.planes[0].distance = std::numeric_limits<float>::infinity();
    spec.brushes.push_back(bad);
    spec.spawn_points.push_back({{0, 0, 25}});
    const auto findings = check_map(build_map(spec, "spec"));
    expect_finding(findings, "degenerate_brushes", FindingSeverity::warning,
                   {"1 of 2", "non-finite 1"});
    EXPECT_FALSE(any_unusable(findings)) << codes(findings);
}

TEST(MapChecks, EveryBrushScaledByAHundredThousandIsAbsurd) {
    // The audit's case: a sound map with every coordinate scaled x1e5.
    MapSpec spec = generate_rooms({});
    for (BrushSpec& brush : spec.brushes) {
        for (visibility::Plane& plane : brush.planes) {
            plane.distance *= 1.0e5f;
        }
    }
    for (SpawnPoint& spawn : spec.spawn_points) {
        spawn.origin *= 1.0e5f;
    }
    const auto findings = check_map(build_map(spec, "gen:rooms x1e5"));
    // At that scale the brushes' planes no longer make polyhedra: nothing occludes or
    // collides, and no spawn point stands in a world.
    for (const char* code :
         {"beyond_world_limit", "no_occluders", "degenerate_brushes", "no_usable_spawn_point"}) {
        EXPECT_NE(find(findings, code), nullptr) << code << "\n" << codes(findings);
    }
    EXPECT_TRUE(any_unusable(findings));
}

} // namespace
} // namespace dsoc::maps
