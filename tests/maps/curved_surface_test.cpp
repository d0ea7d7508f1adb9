// Quake 3 curved patches: decoded from the surfaces lump (and rejected, naming the
// surface, when their sizes or vertices are wrong), kept by the loader when the game
// draws them opaque, and tessellated onto the exact biquadratic Bezier surface.

#include "dsoc/maps/curved_surface.hpp"
#include "dsoc/maps/q3_bsp.hpp"
#include "dsoc/maps/q3_map.hpp"
#include "test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dsoc::maps {
namespace {

using q3::Lump;

/// The small map with a `width` x `height` patch (surface 0, in the world model) on
/// `shader`, its control points a bump over the square [0, 64]^2 at z = 0.
test::BspWriter map_with_patch(int width, int height, std::int32_t shader = 0,
                               std::int32_t num_verts = -1) {
    test::BspWriter w = test::small_map_writer();
    const int points = num_verts >= 0 ? num_verts : width * height;
    for (int i = 0; i < points; ++i) {
        const int row = width > 0 ? i / width : 0;
        const int column = width > 0 ? i % width : 0;
        const float z = (row % 2 == 1 && column % 2 == 1) ? 32.0f : 0.0f;
        // position, st, lightmap st, normal (colour: one more word)
        w.put_f32s(Lump::draw_verts, {32.0f * static_cast<float>(column),
                                      32.0f * static_cast<float>(row), z, 0, 0, 0, 0, 0, 0, 1});
        w.put_i32s(Lump::draw_verts, {-1});
    }
    // shader, fog, type 2 (patch), first vertex, vertices, first index, indexes,
    // lightmap number, lightmap x, y, width, height (12 words); lightmap origin and
    // vectors (12 floats); patch width, height.
    w.put_i32s(Lump::surfaces, {shader, -1, 2, 0, points, 0, 0, 0, 0, 0, 0, 0});
    w.put_f32s(Lump::surfaces, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1});
    w.put_i32s(Lump::surfaces, {width, height});
    w.lumps[static_cast<int>(Lump::models)].clear();
    w.put_f32s(Lump::models, {-256, -256, -16, 256, 256, 256});
    w.put_i32s(Lump::models, {0, 1, 0, 4});
    return w;
}

TEST(CurvedSurfaces, ParserDecodesAPatch) {
    const auto bsp = q3::parse_q3_bsp(map_with_patch(3, 5).build(), "test.bsp");
    ASSERT_TRUE(bsp.ok()) << bsp.error().message();
    ASSERT_EQ(bsp->patches.size(), 1u);
    const q3::Patch& patch = bsp->patches[0];
    EXPECT_EQ(patch.width, 3);
    EXPECT_EQ(patch.height, 5);
    ASSERT_EQ(patch.points.size(), 15u);
    EXPECT_EQ(patch.points[4], glm::vec3(32, 32, 32)); // row 1, column 1
    EXPECT_EQ(patch.points[14], glm::vec3(64, 128, 0));
}

TEST(CurvedSurfaces, ParserNamesABadPatch) {
    struct Case {
        int width, height, shader, num_verts;
        const char* fragment;
    };
    const Case cases[] = {
        {4, 3, 0, -1, "patch of 4 x 3 control points"}, // even side
        {1, 3, 0, -1, "patch of 1 x 3"},                // too small
        {33, 3, 0, 99, "patch of 33 x 3"},              // more than the game's 32 a side
        {3, 3, 0, 8, "with 8 vertices"},                // width x height != vertices
        {3, 3, 9, -1, "shader index 9 out of range"},   // no such shader
    };
    for (const Case& c : cases) {
        const auto bsp = q3::parse_q3_bsp(
            map_with_patch(c.width, c.height, c.shader, c.num_verts).build(), "test.bsp");
        ASSERT_FALSE(bsp.ok()) << c.fragment;
        EXPECT_EQ(bsp.error().lump, q3::lump_label(Lump::surfaces));
        EXPECT_NE(bsp.error().what.find("surface 0"), std::string::npos) << bsp.error().what;
        EXPECT_NE(bsp.error().what.find(c.fragment), std::string::npos) << bsp.error().what;
    }
    // Vertices past the end of the draw vertices lump.
    test::BspWriter w = map_with_patch(3, 3);
    w.lumps[static_cast<int>(Lump::draw_verts)].resize(8 * 44);
    const auto bsp = q3::parse_q3_bsp(w.build(), "test.bsp");
    ASSERT_FALSE(bsp.ok());
    EXPECT_NE(bsp.error().what.find("vertices [0, +9) out of range (8 draw vertices)"),
              std::string::npos)
        << bsp.error().what;
    // Two patches on the same nine vertices: in range one by one, but together they
    // would hold more points than the file has (memory no longer bounded by the input).
    test::BspWriter shared = map_with_patch(3, 3);
    shared.put_i32s(Lump::surfaces, {0, -1, 2, 0, 9, 0, 0, 0, 0, 0, 0, 0});
    shared.put_f32s(Lump::surfaces, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1});
    shared.put_i32s(Lump::surfaces, {3, 3});
    const auto twice = q3::parse_q3_bsp(shared.build(), "test.bsp");
    ASSERT_FALSE(twice.ok());
    EXPECT_NE(twice.error().what.find("surface 1: the patches so far hold 18 control points, "
                                      "more than the 9 draw vertices"),
              std::string::npos)
        << twice.error().what;
}

TEST(CurvedSurfaces, LoaderKeepsTheWorldsOpaquePatches) {
    const auto keep = [](test::BspWriter w) {
        const auto bsp = q3::parse_q3_bsp(w.build(), "test.bsp");
        EXPECT_TRUE(bsp.ok());
        const auto map = map_from_q3_bsp(bsp.value(), "small");
        EXPECT_TRUE(map.ok());
        EXPECT_EQ(map->stats.patches_left_out, 1u);
        EXPECT_EQ(map->stats.opaque_patches, map->opaque_patches.size());
        return map->opaque_patches.size();
    };
    test::BspWriter kept = map_with_patch(3, 5, 0);
    EXPECT_EQ(keep(kept), 1u); // textures/floor: drawn, no script
    const auto map = map_from_q3_bsp(q3::parse_q3_bsp(kept.build(), "test.bsp").value(), "small");
    ASSERT_EQ(map->opaque_patches.size(), 1u);
    EXPECT_EQ(map->opaque_patches[0].width, 3);
    EXPECT_EQ(map->opaque_patches[0].height, 5);
    EXPECT_EQ(map->opaque_patches[0].points[7], glm::vec3(32, 64, 0)); // row 2, column 1
    test::BspWriter trans = map_with_patch(3, 3, 4);
    trans.put_shader("textures/plain", 0, q3::kContentsSolid | q3::kContentsTranslucent);
    EXPECT_EQ(keep(trans), 0u);                   // surfaceparm trans, whatever its name
    EXPECT_EQ(keep(map_with_patch(3, 3, 1)), 0u); // textures/glass: "glass" lets sight through
    EXPECT_EQ(keep(map_with_patch(3, 3, 2)), 0u); // caulk: nodraw
    test::BspWriter door = map_with_patch(3, 3, 0);
    door.lumps[static_cast<int>(Lump::models)].clear();
    door.put_f32s(Lump::models, {-256, -256, -16, 256, 256, 256});
    door.put_i32s(Lump::models, {0, 0, 0, 4}); // the world has no surface: a door's patch
    door.put_f32s(Lump::models, {0, 0, 0, 64, 64, 32});
    door.put_i32s(Lump::models, {0, 1, 0, 0});
    EXPECT_EQ(keep(door), 0u);
}

/// The exact surface of a 3 x 3 patch at parameters (s along a row, t across rows).
glm::vec3 exact(const CurvedSurface& patch, float s, float t) {
    const auto b = [](glm::vec3 a, glm::vec3 m, glm::vec3 c, float u) {
        return (1 - u) * (1 - u) * a + 2 * (1 - u) * u * m + u * u * c;
    };
    glm::vec3 rows[3];
    for (int r = 0; r < 3; ++r) {
        rows[r] = b(patch.points[r * 3], patch.points[r * 3 + 1], patch.points[r * 3 + 2], s);
    }
    return b(rows[0], rows[1], rows[2], t);
}

TEST(CurvedSurfaces, TessellationFollowsTheGridsRowsAndColumns) {
    // 3 wide, 5 high: two patches stacked along the rows. Column 1 of every row bulges
    // in z by its row number, so a swap of rows and columns moves the bulges.
    CurvedSurface tall{3, 5, {}};
    for (int row = 0; row < 5; ++row) {
        for (int column = 0; column < 3; ++column) {
            tall.points.emplace_back(10.0f * static_cast<float>(column),
                                     10.0f * static_cast<float>(row),
                                     column == 1 ? static_cast<float>(row + 1) : 0.0f);
        }
    }
    std::vector<glm::vec3> triangles;
    tessellate(tall, 2, triangles);
    ASSERT_EQ(triangles.size(), 2u * 6u * 4u);
    // The upper patch (rows 2..4) at s = t = 1/2: the exact surface point.
    CurvedSurface upper{3, 3, {tall.points.begin() + 6, tall.points.end()}};
    const glm::vec3 middle = exact(upper, 0.5f, 0.5f);
    bool found = false;
    for (const glm::vec3& v : triangles) {
        found = found || glm::distance(v, middle) < 1e-4f;
    }
    EXPECT_TRUE(found) << "(" << middle.x << ", " << middle.y << ", " << middle.z << ")";
    // Every vertex lies within the grid's bounds: 0..20 across, 0..40 along.
    for (const glm::vec3& v : triangles) {
        EXPECT_LE(v.x, 20.0f);
        EXPECT_LE(v.y, 40.0f);
    }
}

TEST(CurvedSurfaces, TessellationLiesOnTheSurfaceAndSharesEdges) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> coordinate(-100.0f, 100.0f);
    for (int trial = 0; trial < 50; ++trial) {
        CurvedSurface patch{3, 3, {}};
        for (int i = 0; i < 9; ++i) {
            patch.points.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
        }
        const int steps = 1 + trial % 8;
        std::vector<glm::vec3> triangles;
        tessellate(patch, steps, triangles);
        ASSERT_EQ(triangles.size(), static_cast<std::size_t>(6 * steps * steps));
        // Every vertex is a point of the exact surface at a grid parameter.
        for (const glm::vec3& v : triangles) {
            float best = 1e9f;
            for (int i = 0; i <= steps; ++i) {
                for (int j = 0; j <= steps; ++j) {
                    best =
                        std::min(best, glm::distance(v, exact(patch, static_cast<float>(i) / steps,
                                                              static_cast<float>(j) / steps)));
                }
            }
            EXPECT_LT(best, 1e-3f);
        }
        // The four corners are control points.
        for (int corner : {0, 2, 6, 8}) {
            bool found = false;
            for (const glm::vec3& v : triangles) {
                found = found || glm::distance(v, patch.points[corner]) < 1e-4f;
            }
            EXPECT_TRUE(found) << "corner " << corner;
        }
    }
    // A 5 x 3 grid is two patches sharing the column of points 2, 7, 12: both evaluate
    // that edge at the same parameters, so no gap opens between them.
    CurvedSurface wide{5, 3, {}};
    for (int i = 0; i < 15; ++i) {
        wide.points.emplace_back(static_cast<float>(i % 5) * 10.0f,
                                 static_cast<float>(i / 5) * 10.0f, (i % 5) % 2 == 1 ? 7.0f : 0.0f);
    }
    std::vector<glm::vec3> triangles;
    tessellate(wide, 4, triangles);
    ASSERT_EQ(triangles.size(), 2u * 6u * 16u);
    int on_edge_left = 0;
    int on_edge_right = 0;
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        if (triangles[k].x == 20.0f) {
            (k < triangles.size() / 2 ? on_edge_left : on_edge_right) += 1;
        }
    }
    EXPECT_GT(on_edge_left, 0);
    EXPECT_EQ(on_edge_left, on_edge_right);
}

} // namespace
} // namespace dsoc::maps
