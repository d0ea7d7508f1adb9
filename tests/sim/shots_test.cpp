// Hitscan shots (sim/shots.hpp): the nearest living box on the segment, stopped by the
// first wall and by the range; never the shooter, never one not hittable.

#include "dsoc/sim/shots.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <vector>

namespace dsoc::sim {
namespace {

visibility::Aabb cube_at(glm::vec3 centre, float half) {
    return {centre - glm::vec3(half), centre + glm::vec3(half)};
}

maps::CollisionBrush brush_of(const visibility::Aabb& box) {
    maps::CollisionBrush brush;
    brush.bounds = box;
    for (int a = 0; a < 3; ++a) {
        glm::vec3 n(0.0f);
        n[a] = 1.0f;
        brush.planes.push_back({n, box.max[a]});
        brush.planes.push_back({-n, -box.min[a]});
    }
    return brush;
}

struct Range {
    std::vector<visibility::Aabb> boxes;
    std::vector<std::uint8_t> hittable;
    void add(glm::vec3 centre, bool alive = true) {
        boxes.push_back(cube_at(centre, 16.0f));
        hittable.push_back(alive ? 1 : 0);
    }
};

TEST(Shots, ViewDirectionFollowsQuakesAngles) {
    const glm::vec3 east = view_direction(0.0f, 0.0f);
    EXPECT_NEAR(east.x, 1.0f, 1e-6f);
    EXPECT_NEAR(glm::length(east - glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(view_direction(90.0f, 0.0f) - glm::vec3(0, 1, 0)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(view_direction(0.0f, 90.0f) - glm::vec3(0, 0, -1)), 0.0f, 1e-6f)
        << "positive pitch looks down";
    EXPECT_NEAR(glm::length(view_direction(37.0f, -21.0f)), 1.0f, 1e-6f);
}

TEST(Shots, HitTheNearestLivingBoxOnTheLineAndNeverTheShooter) {
    const CollisionWorld open;
    Range r;
    r.add({0, 0, 0});          // 0: the shooter, its eye inside its own box
    r.add({300, 0, 0});        // 1: behind 2
    r.add({200, 0, 0});        // 2: the nearest on the line
    r.add({100, 40, 0});       // 3: beside the line
    r.add({150, 0, 0}, false); // 4: on the line but dead
    const glm::vec3 eye(0, 0, 8);
    const glm::vec3 east(1, 0, 0);
    EXPECT_EQ(first_hit(open, eye, east, 1000.0f, r.boxes, r.hittable, 0),
              std::optional<std::size_t>(2));
    r.hittable[2] = 0;
    EXPECT_EQ(first_hit(open, eye, east, 1000.0f, r.boxes, r.hittable, 0),
              std::optional<std::size_t>(1));
    EXPECT_EQ(first_hit(open, eye, east, 250.0f, r.boxes, r.hittable, 0), std::nullopt)
        << "box 1 starts beyond the range";
    EXPECT_EQ(first_hit(open, eye, -east, 1000.0f, r.boxes, r.hittable, 0), std::nullopt);
    // Shooting from box 1 westwards: 2 is not hittable, 4 is dead, 0 is next.
    EXPECT_EQ(first_hit(open, {300, 0, 8}, -east, 1000.0f, r.boxes, r.hittable, 1),
              std::optional<std::size_t>(0));
}

TEST(Shots, AWallStopsTheShot) {
    const std::vector<maps::CollisionBrush> wall{brush_of({{120, -64, -64}, {136, 64, 64}})};
    const CollisionWorld world(wall);
    Range r;
    r.add({0, 0, 0});
    r.add({200, 0, 0}); // behind the wall
    r.add({100, 0, 0}); // in front of it
    const glm::vec3 eye(0, 0, 8);
    EXPECT_EQ(first_hit(world, eye, {1, 0, 0}, 1000.0f, r.boxes, r.hittable, 0),
              std::optional<std::size_t>(2));
    r.hittable[2] = 0;
    EXPECT_EQ(first_hit(world, eye, {1, 0, 0}, 1000.0f, r.boxes, r.hittable, 0), std::nullopt);
    // Over the wall (well clear of its top edge), the same box is hit.
    const glm::vec3 over = glm::normalize(glm::vec3(200, 0, 0) - glm::vec3(0, 0, 300));
    EXPECT_EQ(first_hit(world, {0, 0, 300}, over, 1000.0f, r.boxes, r.hittable, 0),
              std::optional<std::size_t>(1));
}

} // namespace
} // namespace dsoc::sim
