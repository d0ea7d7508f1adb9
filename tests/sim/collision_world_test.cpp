// Swept-box traces against brushes, checked against brute force: a trace never ends
// inside a brush, the free part of the sweep is free, and box_in_solid agrees with a
// plane-by-plane test over every brush (no grid).

#include "dsoc/maps/generators.hpp"
#include "dsoc/sim/collision_world.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

namespace dsoc::sim {
namespace {

bool brute_in_solid(const maps::Map& map, glm::vec3 p, glm::vec3 mins, glm::vec3 maxs) {
    for (const maps::CollisionBrush& brush : map.collision_brushes) {
        bool inside = true;
        for (const visibility::Plane& plane : brush.planes) {
            glm::vec3 corner;
            for (int a = 0; a < 3; ++a) {
                corner[a] = plane.normal[a] < 0.0f ? maxs[a] : mins[a];
            }
            if (glm::dot(plane.normal, p + corner) - plane.distance >= 0.0f) {
                inside = false;
                break;
            }
        }
        if (inside) {
            return true;
        }
    }
    return false;
}

TEST(CollisionWorld, AgreesWithBruteForce) {
    maps::RoomsParams params;
    params.rooms_x = 4;
    params.rooms_y = 3;
    const maps::Map map = maps::build_map(maps::generate_rooms(params), "rooms");
    const CollisionWorld world(map.collision_brushes);
    EXPECT_EQ(world.brush_count(), map.collision_brushes.size());
    const glm::vec3 mins(-15, -15, -24);
    const glm::vec3 maxs(15, 15, 32);
    std::uint32_t rng = 99;
    auto random = [&](float lo, float hi) {
        rng = rng * 1664525u + 1013904223u;
        return lo + (hi - lo) * static_cast<float>(rng >> 8) / 16777216.0f;
    };
    const visibility::Aabb b = map.bounds;
    int hits = 0;
    for (int i = 0; i < 4000; ++i) {
        const glm::vec3 start(random(b.min.x, b.max.x), random(b.min.y, b.max.y),
                              random(b.min.z, b.max.z));
        const glm::vec3 end =
            start + glm::vec3(random(-300, 300), random(-300, 300), random(-100, 100));
        EXPECT_EQ(world.box_in_solid(start, mins, maxs), brute_in_solid(map, start, mins, maxs));
        if (brute_in_solid(map, start, mins, maxs)) {
            continue;
        }
        const BoxTrace trace = world.trace_box(start, end, mins, maxs);
        EXPECT_FALSE(trace.start_solid);
        EXPECT_FALSE(brute_in_solid(map, trace.end_position, mins, maxs))
            << "trace ended inside a brush";
        for (float f = 0.0f; f <= trace.fraction; f += 0.05f) {
            EXPECT_FALSE(brute_in_solid(map, start + (end - start) * f, mins, maxs));
        }
        if (trace.fraction < 1.0f) {
            ++hits;
            EXPECT_NEAR(glm::length(trace.hit_normal), 1.0f, 1e-4f);
            // Just past the hit (a box length further) the path is blocked somewhere.
        }
    }
    EXPECT_GT(hits, 100);
}

TEST(CollisionWorld, TraceStopsInFrontOfAWall) {
    const auto spec = maps::MapSpec{
        "wall",
        {maps::BrushSpec::box(maps::BrushKind::solid, {{100, -50, -50}, {120, 50, 50}})},
        {}};
    const maps::Map map = maps::build_map(spec, "wall");
    const CollisionWorld world(map.collision_brushes);
    const BoxTrace trace = world.trace_box({0, 0, 0}, {200, 0, 0}, {-10, -10, -10}, {10, 10, 10});
    ASSERT_LT(trace.fraction, 1.0f);
    EXPECT_NEAR(trace.end_position.x, 90.0f - kSurfaceClipEpsilon, 1e-3f);
    EXPECT_EQ(trace.hit_normal, glm::vec3(-1, 0, 0));
    EXPECT_EQ(trace.brush, 0);
    // Past the wall's end in y: nothing hit.
    EXPECT_EQ(world.trace_box({0, 61, 0}, {200, 61, 0}, {-10, -10, -10}, {10, 10, 10}).fraction,
              1.0f);
    // Starting inside.
    const BoxTrace inside = world.trace_box({110, 0, 0}, {110, 0, 0}, {-1, -1, -1}, {1, 1, 1});
    EXPECT_TRUE(inside.start_solid);
    EXPECT_TRUE(inside.all_solid);
    EXPECT_EQ(inside.fraction, 0.0f);
    // Clip brushes are skipped when the mask leaves them out.
    const CollisionWorld none(map.collision_brushes, maps::contents_player_clip);
    EXPECT_EQ(none.brush_count(), 0u);
}

} // namespace
} // namespace dsoc::sim
