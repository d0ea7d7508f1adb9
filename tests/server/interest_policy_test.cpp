#include "dsoc/server/interest_policy.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>

namespace dsoc::server {
namespace {

TEST(InterestPolicy, BroadcastSelectsEverything) {
    ServerConfig c;
    c.bots = 25;
    GameWorld world(c);
    BroadcastPolicy policy;
    std::vector<std::uint32_t> out;
    policy.select(world, Viewer{1, 1, {0, 0, 0}}, out);
    EXPECT_EQ(out.size(), 25u);
    EXPECT_TRUE(std::is_sorted(out.begin(), out.end()));
}

TEST(InterestPolicy, DistanceKeepsExactlyTheEntitiesWithinRadius) {
    ServerConfig c;
    c.bots = 300;
    c.world_half_size = 4000.0f;
    GameWorld world(c);
    const float radius = 1000.0f;
    DistancePolicy policy(radius);
    std::vector<std::uint32_t> out;
    const glm::vec3 eye{100.0f, -200.0f, 50.0f};
    policy.select(world, Viewer{1, 0, eye}, out);
    std::size_t expected = 0;
    for (const Entity& e : world.entities()) {
        const glm::vec3 lo = e.position - e.half_extents;
        const glm::vec3 hi = e.position + e.half_extents;
        const glm::vec3 nearest = glm::clamp(eye, lo, hi);
        const bool inside = glm::length(nearest - eye) <= radius;
        expected += inside ? 1 : 0;
        EXPECT_EQ(std::binary_search(out.begin(), out.end(), e.id), inside) << "entity " << e.id;
    }
    EXPECT_EQ(out.size(), expected);
    // The policy must actually cull something in this world.
    EXPECT_LT(out.size(), world.entities().size() / 2);
    EXPECT_GT(out.size(), 0u);
}

TEST(GameWorld, EntitiesNeverExceedMaxSpeed) {
    ServerConfig c;
    c.bots = 50;
    GameWorld world(c);
    const auto player = world.spawn_player();
    world.set_player_input(player, {10.0f, 10.0f, 0.0f}, 720.0f, 200.0f);
    const float dt = 1.0f / 30.0f;
    for (int t = 0; t < 300; ++t) {
        std::vector<glm::vec3> before;
        for (const auto& e : world.entities()) {
            before.push_back(e.position);
        }
        world.step(dt);
        for (std::size_t i = 0; i < before.size(); ++i) {
            ASSERT_LE(glm::length(world.entities()[i].position - before[i]),
                      c.max_speed * dt * 1.0001f);
        }
    }
    const Entity* p = world.find(player);
    ASSERT_NE(p, nullptr);
    EXPECT_GE(p->yaw_deg, -180.0f);
    EXPECT_LT(p->yaw_deg, 180.0f);
    EXPECT_EQ(p->pitch_deg, 90.0f);
}

} // namespace
} // namespace dsoc::server
