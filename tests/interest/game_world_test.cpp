// GameWorld's reserved player ids: the server tells a client its entity id at hello
// and spawns it at the next tick start, possibly after later-reserved ones.

#include "dsoc/interest/game_world.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace dsoc::interest {
namespace {

bool ids_increasing(const GameWorld& world) {
    return std::is_sorted(world.entities().begin(), world.entities().end(),
                          [](const Entity& a, const Entity& b) { return a.id < b.id; }) &&
           std::adjacent_find(world.entities().begin(), world.entities().end(),
                              [](const Entity& a, const Entity& b) { return a.id == b.id; }) ==
               world.entities().end();
}

TEST(GameWorld, ReservedPlayersSpawnInIdOrderWhateverOrderTheySpawnIn) {
    WorldSettings settings;
    settings.bots = 5;
    GameWorld world(settings, testing::rooms_map());
    const std::size_t bots = world.entities().size();
    const std::uint32_t first = world.reserve_player();
    const std::uint32_t second = world.reserve_player();
    EXPECT_LT(first, second);
    EXPECT_EQ(world.entities().size(), bots); // reserving touches no entity
    EXPECT_EQ(world.find(first), nullptr);

    world.spawn_reserved(second); // the later one first
    const std::uint32_t third = world.spawn_player();
    world.spawn_reserved(first);
    EXPECT_GT(third, second);
    ASSERT_EQ(world.entities().size(), bots + 3);
    EXPECT_TRUE(ids_increasing(world));
    for (const std::uint32_t id : {first, second, third}) {
        const Entity* e = world.find(id);
        ASSERT_NE(e, nullptr) << id;
        EXPECT_EQ(e->id, id);
        EXPECT_EQ(e->kind, EntityKind::player);
    }
    world.remove(second);
    EXPECT_EQ(world.find(second), nullptr);
    EXPECT_NE(world.find(first), nullptr);
    EXPECT_TRUE(ids_increasing(world));
}

TEST(GameWorld, APlayerWhoTouchesAHazardRespawnsAtTheNextSpawnPoint) {
    // A pit under the first spawn point: the player put there dies on its first step
    // and is back at the next spawn point, flagged as a teleport for that tick only.
    auto map = std::make_shared<maps::Map>(*testing::rooms_map());
    ASSERT_GE(map->spawn_points.size(), 2u);
    WorldSettings settings;
    settings.bots = 0;
    // The world hands out spawn points round robin from seed % count.
    const std::size_t first = settings.seed % map->spawn_points.size();
    const glm::vec3 pit = map->spawn_points[first].origin;
    map->hazards.push_back(
        {visibility::Aabb{pit - glm::vec3(40.0f), pit + glm::vec3(40.0f)}, "test pit"});
    for (std::size_t i = 0; i < map->spawn_points.size(); ++i) {
        if (i != first) {
            ASSERT_GT(glm::length(map->spawn_points[i].origin - pit), 200.0f);
        }
    }
    GameWorld world(settings, map);
    const std::uint32_t id = world.spawn_player();
    world.step(1.0f / 30.0f);
    const Entity* e = world.find(id);
    ASSERT_NE(e, nullptr);
    EXPECT_TRUE(e->teleported);
    EXPECT_GT(glm::length(e->move.position - pit), 150.0f);
    world.step(1.0f / 30.0f);
    EXPECT_FALSE(world.find(id)->teleported);
}

} // namespace
} // namespace dsoc::interest
