#include "dsoc/visibility/convex_polyhedron.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace dsoc::visibility {
namespace {

std::vector<Plane> box_planes(glm::vec3 lo, glm::vec3 hi) {
    return {{{1, 0, 0}, hi.x},   {{-1, 0, 0}, -lo.x}, {{0, 1, 0}, hi.y},
            {{0, -1, 0}, -lo.y}, {{0, 0, 1}, hi.z},   {{0, 0, -1}, -lo.z}};
}

/// Every face loop is counter-clockwise seen from outside and lies on its plane;
/// every vertex satisfies every plane.
void expect_consistent(const ConvexPolyhedron& poly, float eps = 1e-3f) {
    for (const glm::vec3& v : poly.vertices()) {
        EXPECT_TRUE(poly.contains(v, eps));
        EXPECT_TRUE(poly.bounds().contains(v));
        EXPECT_LE(glm::length(v - poly.bounding_sphere().center), poly.bounding_sphere().radius);
    }
    for (const PolyhedronFace& face : poly.faces()) {
        ASSERT_GE(face.vertex_indices.size(), 3u);
        glm::vec3 newell(0.0f);
        for (std::size_t i = 0; i < face.vertex_indices.size(); ++i) {
            const glm::vec3 a = poly.vertices()[face.vertex_indices[i]];
            const glm::vec3 b =
                poly.vertices()[face.vertex_indices[(i + 1) % face.vertex_indices.size()]];
            EXPECT_NEAR(face.plane.signed_distance(a), 0.0f, eps);
            newell += glm::cross(a, b);
        }
        EXPECT_GT(glm::dot(newell, face.plane.normal), 0.0f) << "face not CCW from outside";
    }
}

TEST(ConvexPolyhedron, UnitCubeFromPlanes) {
    const auto planes = box_planes({0, 0, 0}, {1, 2, 3});
    PolyhedronResult result;
    const auto poly = ConvexPolyhedron::from_planes(planes, result);
    ASSERT_TRUE(result.ok()) << result.detail;
    EXPECT_EQ(poly.vertices().size(), 8u);
    EXPECT_EQ(poly.faces().size(), 6u);
    for (const auto& f : poly.faces()) {
        EXPECT_EQ(f.vertex_indices.size(), 4u);
    }
    EXPECT_NEAR(poly.bounds().min.x, 0.0f, 1e-5f);
    EXPECT_NEAR(poly.bounds().max.z, 3.0f, 1e-5f);
    EXPECT_TRUE(poly.contains({0.5f, 1.0f, 1.5f}));
    EXPECT_TRUE(poly.contains({1.0f, 1.0f, 1.5f}));
    EXPECT_FALSE(poly.contains({1.01f, 1.0f, 1.5f}));
    expect_consistent(poly);
}

TEST(ConvexPolyhedron, FromAabbMatchesBox) {
    const Aabb box{{-5, 2, 7}, {1, 4, 9}};
    const auto poly = ConvexPolyhedron::from_aabb(box);
    ASSERT_FALSE(poly.is_empty());
    EXPECT_EQ(poly.vertices().size(), 8u);
    EXPECT_EQ(poly.faces().size(), 6u);
    EXPECT_NEAR(poly.bounds().min.y, 2.0f, 1e-5f);
    EXPECT_NEAR(poly.bounds().max.x, 1.0f, 1e-5f);
    expect_consistent(poly);
    EXPECT_TRUE(ConvexPolyhedron::from_aabb(Aabb::empty()).is_empty());
}

TEST(ConvexPolyhedron, UnnormalizedNormalsAreNormalized) {
    auto planes = box_planes({0, 0, 0}, {2, 2, 2});
    for (auto& p : planes) {
        p.normal *= 3.0f;
        p.distance *= 3.0f;
    }
    PolyhedronResult result;
    const auto poly = ConvexPolyhedron::from_planes(planes, result);
    ASSERT_TRUE(result.ok()) << result.detail;
    EXPECT_NEAR(glm::length(poly.planes()[0].normal), 1.0f, 1e-6f);
    EXPECT_NEAR(poly.bounds().max.x, 2.0f, 1e-4f);
}

TEST(ConvexPolyhedron, TetrahedronAndBevelsAndDuplicates) {
    // Tetrahedron x,y,z >= 0, x+y+z <= 1, plus a redundant bevel and a duplicate plane.
    std::vector<Plane> planes = {
        {{-1, 0, 0}, 0},    {{0, -1, 0}, 0},
        {{0, 0, -1}, 0},    {glm::normalize(glm::vec3(1, 1, 1)), 1.0f / std::sqrt(3.0f)},
        {{1, 0, 0}, 5.0f},   // redundant: touches nothing
        {{-1, 0, 0}, 0.0f},  // duplicate of plane 0
        {{0, 0, -2}, 0.0f}}; // duplicate of plane 2 (scaled)
    PolyhedronResult result;
    const auto poly = ConvexPolyhedron::from_planes(planes, result);
    ASSERT_TRUE(result.ok()) << result.detail;
    EXPECT_EQ(poly.vertices().size(), 4u);
    EXPECT_EQ(poly.faces().size(), 4u);
    EXPECT_EQ(poly.planes().size(), planes.size());
    expect_consistent(poly);
}

TEST(ConvexPolyhedron, TooFewPlanes) {
    const std::vector<Plane> planes = {{{1, 0, 0}, 1}, {{-1, 0, 0}, 1}, {{0, 1, 0}, 1}};
    PolyhedronResult result;
    const auto poly = ConvexPolyhedron::from_planes(planes, result);
    EXPECT_EQ(result.error, PolyhedronError::too_few_planes);
    EXPECT_TRUE(poly.is_empty());
    EXPECT_FALSE(result.detail.empty());
}

TEST(ConvexPolyhedron, NaNInfAndZeroNormalAreReported) {
    for (int which = 0; which < 3; ++which) {
        auto planes = box_planes({0, 0, 0}, {1, 1, 1});
        if (which == 0) {
            planes[3].normal.y = std::numeric_limits<float>::quiet_NaN();
        } else if (which == 1) {
            planes[2].distance = std::numeric_limits<float>::infinity();
        } else {
            planes[4].normal = glm::vec3(0.0f);
        }
        PolyhedronResult result;
        const auto poly = ConvexPolyhedron::from_planes(planes, result);
        EXPECT_EQ(result.error, PolyhedronError::non_finite_plane) << which;
        EXPECT_TRUE(poly.is_empty());
        EXPECT_NE(result.detail.find("plane"), std::string::npos) << result.detail;
    }
}

TEST(ConvexPolyhedron, UnboundedIsReported) {
    // Five sides of a box: open towards +z.
    auto planes = box_planes({0, 0, 0}, {1, 1, 1});
    planes.erase(planes.begin() + 4);
    PolyhedronResult result;
    const auto poly = ConvexPolyhedron::from_planes(planes, result);
    EXPECT_EQ(result.error, PolyhedronError::unbounded) << result.detail;
    EXPECT_TRUE(poly.is_empty());
    // A wedge: all normals in one half-space.
    const std::vector<Plane> wedge = {
        {{1, 0, 0}, 1}, {{0, 1, 0}, 1}, {{0, 0, 1}, 1}, {glm::normalize(glm::vec3(1, 1, 1)), 1}};
    (void)ConvexPolyhedron::from_planes(wedge, result);
    EXPECT_EQ(result.error, PolyhedronError::unbounded) << result.detail;
}

TEST(ConvexPolyhedron, EmptyAndSliverAreReported) {
    // Contradictory slabs: x <= 0 and x >= 1.
    auto planes = box_planes({0, 0, 0}, {1, 1, 1});
    planes[0].distance = 0.0f;
    planes[1].distance = -1.0f;
    PolyhedronResult result;
    auto poly = ConvexPolyhedron::from_planes(planes, result);
    EXPECT_EQ(result.error, PolyhedronError::empty) << result.detail;
    EXPECT_TRUE(poly.is_empty());
    // A sliver thinner than the tolerance.
    planes = box_planes({0, 0, 0}, {1, 1, 0.001f});
    poly = ConvexPolyhedron::from_planes(planes, result, 1.0f / 64.0f);
    EXPECT_EQ(result.error, PolyhedronError::empty) << result.detail;
    // The same slab with a smaller tolerance is fine.
    poly = ConvexPolyhedron::from_planes(planes, result, 1.0e-4f);
    EXPECT_TRUE(result.ok()) << result.detail;
    // Coincident opposite planes: zero thickness.
    planes = box_planes({0, 0, 0}, {1, 1, 0});
    poly = ConvexPolyhedron::from_planes(planes, result);
    EXPECT_EQ(result.error, PolyhedronError::empty) << result.detail;
}

TEST(ConvexPolyhedron, RandomBrushesWithBevelsAreConsistent) {
    // Random cuts of a box, the way Quake 3 brushes with bevel planes look.
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    int built = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const glm::vec3 c(unit(rng) * 1000.0f, unit(rng) * 1000.0f, unit(rng) * 300.0f);
        const glm::vec3 h(8.0f + 64.0f * std::abs(unit(rng)), 8.0f + 64.0f * std::abs(unit(rng)),
                          8.0f + 64.0f * std::abs(unit(rng)));
        auto planes = box_planes(c - h, c + h);
        const int cuts = static_cast<int>(std::abs(unit(rng)) * 20.0f);
        for (int k = 0; k < cuts; ++k) {
            glm::vec3 n(unit(rng), unit(rng), unit(rng));
            if (glm::length(n) < 0.1f) {
                continue;
            }
            n = glm::normalize(n);
            // Through a point inside the box, keeping the centre, so the solid stays
            // non-empty.
            const glm::vec3 p = c + h * glm::vec3(unit(rng), unit(rng), unit(rng)) * 0.5f;
            if (glm::dot(n, c - p) > 0.0f) {
                n = -n;
            }
            planes.push_back({n, glm::dot(n, p)});
            if (k % 3 == 0) {
                planes.push_back(planes.back()); // exact duplicate
            }
        }
        PolyhedronResult result;
        const auto poly = ConvexPolyhedron::from_planes(planes, result);
        if (!result.ok()) {
            EXPECT_EQ(result.error, PolyhedronError::empty) << result.detail;
            continue;
        }
        ++built;
        expect_consistent(poly, 2e-2f);
        // Euler's formula for a convex polyhedron: V - E + F = 2.
        std::size_t edge_ends = 0;
        for (const auto& f : poly.faces()) {
            edge_ends += f.vertex_indices.size();
        }
        const long v = static_cast<long>(poly.vertices().size());
        const long f = static_cast<long>(poly.faces().size());
        EXPECT_EQ(v - static_cast<long>(edge_ends / 2) + f, 2) << "trial " << trial;
        // Random interior points of the original constraints are contained.
        for (int s = 0; s < 10; ++s) {
            const glm::vec3 p = c + h * glm::vec3(unit(rng), unit(rng), unit(rng));
            bool inside = true;
            for (const auto& pl : planes) {
                inside = inside && pl.signed_distance(p) <= -1e-3f;
            }
            if (inside) {
                EXPECT_TRUE(poly.contains(p));
            }
        }
    }
    EXPECT_GT(built, 200);
}

TEST(ConvexPolyhedron, ErrorNames) {
    EXPECT_STREQ(to_string(PolyhedronError::none), "none");
    EXPECT_STREQ(to_string(PolyhedronError::unbounded), "unbounded");
    EXPECT_STREQ(to_string(PolyhedronError::empty), "empty");
    EXPECT_STREQ(to_string(PolyhedronError::too_few_planes), "too_few_planes");
    EXPECT_STREQ(to_string(PolyhedronError::non_finite_plane), "non_finite_plane");
}

} // namespace
} // namespace dsoc::visibility
