#include "dsoc/visibility/occluder_world.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <vector>

namespace dsoc::visibility {
namespace {

std::vector<Plane> box_planes(glm::vec3 lo, glm::vec3 hi) {
    return {{{1, 0, 0}, hi.x},   {{-1, 0, 0}, -lo.x}, {{0, 1, 0}, hi.y},
            {{0, -1, 0}, -lo.y}, {{0, 0, 1}, hi.z},   {{0, 0, -1}, -lo.z}};
}

TEST(OccluderWorld, EdgesPairFacesOnABox) {
    OccluderWorld world;
    const OccluderId id = world.add(ConvexPolyhedron::from_aabb({{0, 0, 0}, {1, 2, 3}}));
    ASSERT_EQ(id, 0u);
    EXPECT_EQ(world.edges(id).size(), 12u);
    EXPECT_EQ(world.face_planes(id).size(), 6u);
    EXPECT_EQ(world.solid_planes(id).size(), 6u);
    EXPECT_TRUE(world.is_closed(id));
    EXPECT_EQ(world.add(ConvexPolyhedron{}), OccluderWorld::kInvalid);
    EXPECT_EQ(world.size(), 1u);
}

TEST(OccluderWorld, SliverCutKeepsTheSolidTight) {
    // A box whose top is cut by a plane tilted by a hair: the wedge it removes is
    // thinner than the merge tolerance, so no face survives on it, but the solid the
    // rasterizer sees must still exclude the wedge.
    auto planes = box_planes({0, 0, 0}, {64, 64, 64});
    const glm::vec3 n = glm::normalize(glm::vec3(0.0001f, 0.0f, 1.0f));
    planes.push_back({n, glm::dot(n, glm::vec3(0.0f, 0.0f, 64.0f))});
    PolyhedronResult result;
    auto poly = ConvexPolyhedron::from_planes(planes, result, 1.0f / 64.0f);
    ASSERT_TRUE(result.ok()) << result.detail;
    OccluderWorld world;
    const OccluderId id = world.add(std::move(poly));
    const glm::vec3 in_wedge(63.9f, 32.0f, 63.997f); // inside the box, outside the cut
    bool inside_solid = true;
    for (const Plane& p : world.solid_planes(id)) {
        inside_solid = inside_solid && p.signed_distance(in_wedge) <= 0.0f;
    }
    EXPECT_FALSE(inside_solid);
}

TEST(OccluderWorld, QuakeScaleBrushWithBevels) {
    // Far from the origin, with axial bevels touching edges (redundant planes).
    const glm::vec3 lo(60000.0f, -60000.0f, 4000.0f);
    const glm::vec3 hi = lo + glm::vec3(128.0f, 16.0f, 256.0f);
    auto planes = box_planes(lo, hi);
    const glm::vec3 bevel = glm::normalize(glm::vec3(1, 1, 0));
    planes.push_back({bevel, glm::dot(bevel, glm::vec3(hi.x, hi.y, 0.0f))}); // touches an edge
    planes.push_back(planes[0]);                                             // duplicate
    PolyhedronResult result;
    auto poly = ConvexPolyhedron::from_planes(planes, result);
    ASSERT_TRUE(result.ok()) << result.detail;
    EXPECT_EQ(poly.vertices().size(), 8u);
    EXPECT_EQ(poly.faces().size(), 6u);
    OccluderWorld world;
    const OccluderId id = world.add(std::move(poly));
    EXPECT_TRUE(world.is_closed(id));             // a touching bevel does not cut
    EXPECT_EQ(world.solid_planes(id).size(), 7u); // faces + the bevel, not the duplicate
}

} // namespace
} // namespace dsoc::visibility
