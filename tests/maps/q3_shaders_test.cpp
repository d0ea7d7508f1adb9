// Shader scripts: which shaders let sight through, by the renderer's rule, and the
// maps they change (docs/maps.md, "Shader scripts").

#include "dsoc/maps/map_source.hpp"
#include "dsoc/maps/q3_map.hpp"
#include "dsoc/maps/q3_shaders.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace dsoc::maps {
namespace {

using test::kOpenArenaPak;

ShaderSight sight_of(std::string_view text, std::string_view name) {
    ShaderScripts scripts;
    const auto problem = scripts.add(text, "test.shader");
    EXPECT_FALSE(problem.has_value()) << problem->message();
    const auto sight = scripts.sight(name);
    EXPECT_TRUE(sight.has_value()) << name << " not defined";
    return sight.value_or(ShaderSight::opaque);
}

TEST(ShaderScripts, AFirstStageThatCoversWhatIsBehindIsOpaqueWhateverLaterStagesBlend) {
    // As OpenArena's patch10_beatup4_alpha-like walls: the lightmap, then the texture
    // blended onto it.
    EXPECT_EQ(sight_of("textures/w/wall\n{\n  surfaceparm metalsteps\n  {\n    map $lightmap\n"
                       "    rgbGen identity\n  }\n  {\n    map textures/w/wall.tga\n"
                       "    blendFunc GL_DST_COLOR GL_SRC_ALPHA\n  }\n}\n",
                       "textures/w/wall"),
              ShaderSight::opaque);
    EXPECT_EQ(sight_of("w { { map w.tga blendFunc GL_ONE GL_ZERO } }", "w"), ShaderSight::opaque);
}

TEST(ShaderScripts, AnAlphaTestedOrBlendedFirstStageLetsSightThrough) {
    EXPECT_EQ(sight_of("textures/g/grate\n{\n  cull none\n  {\n    map textures/g/grate.tga\n"
                       "    alphaFunc GE128\n    depthWrite\n  }\n  {\n    map $lightmap\n"
                       "    blendFunc filter\n    depthFunc equal\n  }\n}\n",
                       "textures/g/grate"),
              ShaderSight::see_through);
    for (const std::string blend :
         {"add", "filter", "blend", "GL_ONE GL_ONE", "GL_SRC_ALPHA GL_ONE_MINUS_SRC_ALPHA",
          "gl_dst_color gl_zero"}) {
        EXPECT_EQ(sight_of("w\n{\n {\n  map w.tga\n  blendFunc " + blend + "\n }\n}\n", "w"),
                  ShaderSight::see_through)
            << blend;
    }
}

TEST(ShaderScripts, SkiesAreOpaqueAndShadersThatDrawNothingOrMoveAreNot) {
    EXPECT_EQ(sight_of("sky { surfaceparm sky { map clouds.tga blendFunc add } }", "sky"),
              ShaderSight::opaque);
    EXPECT_EQ(sight_of("sky2 { skyparms - 512 - { map c.tga blendFunc GL_ONE GL_ONE } }", "sky2"),
              ShaderSight::opaque);
    EXPECT_EQ(sight_of("empty { surfaceparm trans }", "empty"), ShaderSight::see_through);
    EXPECT_EQ(sight_of("hidden { surfaceparm nodraw { map x.tga } }", "hidden"),
              ShaderSight::see_through);
    EXPECT_EQ(sight_of("flag { deformVertexes wave 100 sin 0 3 0 0.5 { map f.tga } }", "flag"),
              ShaderSight::see_through);
    EXPECT_EQ(sight_of("lit { deformVertexes normal 0.5 0.1 { map f.tga } }", "lit"),
              ShaderSight::opaque);
    EXPECT_EQ(sight_of("mirror { portal { map m.tga } }", "mirror"), ShaderSight::see_through);
}

TEST(ShaderScripts, CommentsQuotesAndCaseAreReadAsQuake3ReadsThem) {
    const std::string text =
        "// a grate\n/* alphaFunc GE128 in a comment\n does nothing */\n\x1a\x01"
        "\"Textures/Q/Plain\" // trailing\n{\n { map q.tga // alphaFunc\n"
        " }\n}\n";
    ShaderScripts scripts;
    ASSERT_FALSE(scripts.add(text, "q.shader").has_value());
    EXPECT_EQ(scripts.sight("textures/q/PLAIN"), ShaderSight::opaque);
    EXPECT_EQ(scripts.sight("textures\\q\\plain.tga"), ShaderSight::opaque) << "as R_FindShader";
    EXPECT_EQ(scripts.size(), 1u);
    EXPECT_TRUE(scripts.complete());
}

TEST(ShaderScripts, ANameDefinedTwiceLetsSightThroughIfEitherDefinitionDoes) {
    const std::string opaque = "w { { map w.tga } }\n";
    const std::string through = "w { { map w.tga alphaFunc GT0 } }\n";
    for (const auto& [first, second] : {std::pair{opaque, through}, std::pair{through, opaque}}) {
        ShaderScripts scripts;
        ASSERT_FALSE(scripts.add(first, "a.shader").has_value());
        ASSERT_FALSE(scripts.add(second, "b.shader").has_value());
        EXPECT_EQ(scripts.sight("w"), ShaderSight::see_through);
    }
}

TEST(ShaderScripts, MalformedTextIsNamedByLineAndKeepsWhatCameBefore) {
    const struct {
        std::string text;
        std::string line;
        std::string what;
    } cases[] = {
        {"good { { map g.tga } }\nbad\n", "line 2", "no body"},
        {"good { { map g.tga } }\n\nopen {\n { map o.tga }\n", "line 3", "not closed"},
        {"good { { map g.tga } }\nnest {\n {\n  {\n", "line 4", "a stage inside a stage"},
        {"good { { map g.tga } }\n}\n", "line 2", "where a shader name belongs"},
    };
    for (const auto& c : cases) {
        ShaderScripts scripts;
        const auto problem = scripts.add(c.text, "broken.shader");
        ASSERT_TRUE(problem.has_value()) << c.text;
        EXPECT_EQ(problem->file, "broken.shader");
        EXPECT_EQ(problem->lump, c.line) << c.text;
        EXPECT_NE(problem->what.find(c.what), std::string::npos) << problem->what;
        EXPECT_FALSE(scripts.complete());
        EXPECT_EQ(scripts.sight("good"), ShaderSight::opaque) << "kept from before the fault";
    }
}

TEST(ShaderScripts, WithoutAScriptAShaderIsOpaqueOnlyWhenTheGamesScriptsWereReadWhole) {
    ShaderScripts whole;
    ASSERT_FALSE(whole.add("g { { map g.tga alphaFunc GE128 } }", "a.shader").has_value());
    EXPECT_TRUE(lets_sight_through("g", &whole));
    EXPECT_FALSE(lets_sight_through("textures/base_floor/clanggrate", &whole)) << "no script";
    // No scripts, or scripts not read whole: the name decides.
    ShaderScripts broken;
    ASSERT_FALSE(broken.add("g { { map g.tga } }", "a.shader").has_value());
    broken.mark_incomplete();
    for (const ShaderScripts* scripts :
         {static_cast<const ShaderScripts*>(nullptr), static_cast<const ShaderScripts*>(&broken)}) {
        EXPECT_TRUE(lets_sight_through("textures/base_floor/clanggrate", scripts));
        EXPECT_TRUE(lets_sight_through("textures/x/Window_2", scripts));
        EXPECT_FALSE(lets_sight_through("textures/base_wall/concrete", scripts));
    }
    EXPECT_FALSE(lets_sight_through("g", &broken)) << "a script's answer still stands";
}

/// Every .pk3 of the OpenArena install, as the map search reads them.
std::vector<std::filesystem::path> openarena_archives() {
    std::vector<std::filesystem::path> out;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(kOpenArenaPak.parent_path(), ec)) {
        if (entry.path().extension() == ".pk3") {
            out.push_back(entry.path());
        }
    }
    return out;
}

#define DSOC_REQUIRE_OPENARENA_SCRIPTS()                                                           \
    do {                                                                                           \
        DSOC_REQUIRE_OPENARENA();                                                                  \
        if (!std::filesystem::exists(kOpenArenaPak.parent_path() / "pak0.pk3")) {                  \
            GTEST_SKIP() << "OpenArena's shader scripts (pak0.pk3, Debian openarena-data) are "    \
                            "not installed: scripts/setup installs them";                          \
        }                                                                                          \
    } while (false)

TEST(ShaderScriptsOfOpenArena, AreReadWholeAndTellGratesFromWalls) {
    DSOC_REQUIRE_OPENARENA_SCRIPTS();
    const ShaderScriptsRead read = read_shader_scripts(openarena_archives());
    EXPECT_TRUE(read.problems.empty()) << read.problems.front().message();
    EXPECT_TRUE(read.scripts.complete());
    EXPECT_GT(read.scripts.size(), 1000u);
    EXPECT_EQ(read.scripts.sight("textures/base_floor/cybergrate2"), ShaderSight::see_through);
    EXPECT_EQ(read.scripts.sight("textures/base_wall/bluemetal2_shiny_trans"), ShaderSight::opaque)
        << "'trans' in the name, opaque in the script";
}

// oa_bases3plus3's walls are drawn with "patch10_beatup4_alpha", which has no script (the
// game draws its image opaque): by name they looked see-through, and the map had 224
// occluders of its 409 solid brushes, so the oracle saw through walls the compiler's PVS
// (rightly) calls walls.
TEST(ShaderScriptsOfOpenArena, MakeTheWallsOfAMapWhoseTextureNameSoundsSeeThroughOcclude) {
    DSOC_REQUIRE_OPENARENA_SCRIPTS();
    const ShaderScriptsRead read = read_shader_scripts(openarena_archives());
    const auto by_name = load_q3_map_from_pk3(kOpenArenaPak, "oa_bases3plus3");
    const auto by_script = load_q3_map_from_pk3(kOpenArenaPak, "oa_bases3plus3", &read.scripts);
    ASSERT_TRUE(by_name.ok() && by_script.ok());
    EXPECT_EQ(by_name->stats.shader_scripts, 0u);
    EXPECT_EQ(by_script->stats.shader_scripts, read.scripts.scripts());
    EXPECT_GT(by_name->stats.see_through_skipped, 150u);
    EXPECT_LT(by_script->stats.see_through_skipped, 10u);
    EXPECT_GT(by_script->occluders.size(), by_name->occluders.size() + 150);
    // load_map() reads the scripts of the search path itself.
    const auto loaded = load_map("oa_bases3plus3", MapSearch{{kOpenArenaPak.parent_path()}});
    ASSERT_TRUE(loaded.ok()) << loaded.error().message();
    EXPECT_EQ(loaded->occluders.size(), by_script->occluders.size());
    EXPECT_TRUE(loaded->shader_script_problems.empty());
}

} // namespace
} // namespace dsoc::maps
