// GameWorld's reserved player ids: the server tells a client its entity id at hello
// and spawns it at the next tick start, possibly after later-reserved ones; spawns and
// removals in a batch give the world of one by one; ids never wrap. Its step
// gives the same world whether the moves run one by one or through a parallel for.

#include "dsoc/interest/game_world.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <thread>

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

/// Whether `a` and `b` hold the same entities, field for field as a spawn or removal
/// leaves them.
void expect_same_entities(const GameWorld& a, const GameWorld& b) {
    ASSERT_EQ(a.entities().size(), b.entities().size());
    for (std::size_t i = 0; i < a.entities().size(); ++i) {
        const Entity& x = a.entities()[i];
        const Entity& y = b.entities()[i];
        EXPECT_TRUE(x.id == y.id && x.kind == y.kind && x.move.position == y.move.position &&
                    x.move.velocity == y.move.velocity && x.yaw_deg == y.yaw_deg &&
                    x.team == y.team && x.health == y.health)
            << "entity " << i << ": " << x.id << " and " << y.id;
        const Entity* found = b.find(x.id);
        ASSERT_NE(found, nullptr) << x.id;
        EXPECT_EQ(found->id, x.id);
    }
}

TEST(GameWorld, SpawnsAndRemovalsInABatchGiveTheWorldOfOneByOne) {
    WorldSettings settings;
    settings.bots = 20;
    settings.teams = 2;
    GameWorld single(settings, testing::rooms_map());
    GameWorld batch(settings, testing::rooms_map());
    std::vector<std::uint32_t> ids;
    for (int i = 0; i < 300; ++i) {
        ids.push_back(single.reserve_player());
        ASSERT_EQ(batch.reserve_player(), ids.back());
    }
    // Joins arrive in any order; the world spawns them in id order (the spawn points
    // are dealt in that order), an id given twice once.
    std::vector<std::uint32_t> shuffled = ids;
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(7));
    shuffled.push_back(shuffled.front());
    for (const std::uint32_t id : ids) {
        single.spawn_reserved(id);
    }
    batch.spawn_reserved(shuffled);
    EXPECT_TRUE(ids_increasing(batch));
    expect_same_entities(single, batch);

    // Every other player and a few bots leave, with an unknown id and a repeat.
    std::vector<std::uint32_t> leaving = {1, 5, 999'999};
    for (std::size_t i = 0; i < ids.size(); i += 2) {
        leaving.push_back(ids[i]);
    }
    leaving.push_back(ids[0]);
    for (const std::uint32_t id : leaving) {
        single.remove(id);
    }
    batch.remove(leaving);
    EXPECT_TRUE(ids_increasing(batch));
    expect_same_entities(single, batch);
    EXPECT_EQ(batch.find(ids[0]), nullptr);

    // And the next spawn point dealt is the same.
    EXPECT_EQ(single.spawn_player(), batch.spawn_player());
    expect_same_entities(single, batch);

    // Ids of an earlier block joined after those of a later one (two gateways' blocks)
    // go in among the entities, and every one is found by its id.
    std::vector<std::uint32_t> early;
    std::vector<std::uint32_t> late;
    for (int i = 0; i < 40; ++i) {
        (i < 20 ? early : late).push_back(single.reserve_player());
        ASSERT_EQ(batch.reserve_player(), (i < 20 ? early : late).back());
    }
    for (const auto* block : {&late, &early}) {
        for (const std::uint32_t id : *block) {
            single.spawn_reserved(id);
        }
        batch.spawn_reserved(*block);
        EXPECT_TRUE(ids_increasing(batch));
        expect_same_entities(single, batch);
    }
    for (const Entity& e : single.entities()) {
        ASSERT_NE(batch.find(e.id), nullptr) << e.id;
        EXPECT_EQ(batch.find(e.id)->id, e.id);
    }
}

TEST(GameWorld, IdsNeverWrapPast32Bits) {
    WorldSettings settings;
    settings.bots = 0;
    GameWorld world(settings, testing::rooms_map());
    // A mirror takes the next id as given: one close to the end.
    world.mirror({}, 0, UINT32_MAX - 10);
    EXPECT_EQ(world.ids_left(), 10u);
    EXPECT_EQ(world.reserve_players(11), 0u); // would hand out id 2^32 - 1, then 0
    EXPECT_EQ(world.next_id(), UINT32_MAX - 10);
    EXPECT_EQ(world.reserve_players(9), UINT32_MAX - 10);
    EXPECT_EQ(world.reserve_player(), UINT32_MAX - 1);
    EXPECT_EQ(world.ids_left(), 0u);
    EXPECT_EQ(world.reserve_player(), 0u);
    EXPECT_EQ(world.next_id(), UINT32_MAX);
}

/// The rooms map with a pit under the first spawn point, and a player put there: it
/// dies on its first step (`respawn_delay_ticks` as given; no bots).
struct DyingPlayer {
    std::shared_ptr<maps::Map> map = std::make_shared<maps::Map>(*testing::rooms_map());
    glm::vec3 pit{0.0f};
    std::unique_ptr<GameWorld> world;
    std::uint32_t id = 0;

    explicit DyingPlayer(int respawn_delay_ticks) {
        WorldSettings settings;
        settings.bots = 0;
        settings.respawn_delay_ticks = respawn_delay_ticks;
        world = std::make_unique<GameWorld>(settings, map);
        // The world hands out spawn points round robin from seed % count. The pit comes
        // after the world chose its spawn points (one in a hazard would not be used:
        // sim/footing.hpp), so the player is put into it.
        pit = testing::add_pit_at_spawn(*map, settings.seed % map->spawn_points.size());
        id = world->spawn_player();
    }
};

TEST(GameWorld, NoPlayerIsPutAtASpawnPointWithoutFooting) {
    // A pit at every other spawn point before the world starts: no player is put there
    // (round robin over the rest), and so none dies on its first step.
    auto map = std::make_shared<maps::Map>(*testing::rooms_map());
    ASSERT_GE(map->spawn_points.size(), 4u);
    std::vector<glm::vec3> pits;
    for (std::size_t i = 0; i < map->spawn_points.size(); i += 2) {
        pits.push_back(testing::add_pit_at_spawn(*map, i));
    }
    WorldSettings settings;
    settings.bots = 0;
    GameWorld world(settings, map);
    std::vector<std::uint32_t> players;
    for (std::size_t i = 0; i < 2 * map->spawn_points.size(); ++i) {
        players.push_back(world.spawn_player());
    }
    world.step(1.0f / 30.0f);
    for (const std::uint32_t id : players) {
        const Entity* e = world.find(id);
        ASSERT_NE(e, nullptr);
        EXPECT_FALSE(e->teleported) << "player " << id << " died on its first step";
        for (const glm::vec3& pit : pits) {
            EXPECT_GT(glm::length(e->move.position - pit), 100.0f) << "player " << id;
        }
    }
}

TEST(GameWorld, APlayerWhoTouchesAHazardRespawnsAtTheNextSpawnPoint) {
    // Without a delay the player is back at the next spawn point at once, flagged as a
    // teleport for that tick only.
    DyingPlayer dying(0);
    for (const auto& spawn : dying.map->spawn_points) {
        if (spawn.origin != dying.pit) {
            ASSERT_GT(glm::length(spawn.origin - dying.pit), 200.0f);
        }
    }
    GameWorld& world = *dying.world;
    world.step(1.0f / 30.0f);
    const Entity* e = world.find(dying.id);
    ASSERT_NE(e, nullptr);
    EXPECT_TRUE(e->teleported);
    EXPECT_FALSE(e->respawn.has_value());
    EXPECT_GT(glm::length(e->move.position - dying.pit), 150.0f);
    world.step(1.0f / 30.0f);
    EXPECT_FALSE(world.find(dying.id)->teleported);
}

TEST(GameWorld, ADeadPlayerIsPutAtItsSpawnPointOnlyAfterTheRespawnDelay) {
    // With a delay the spawn point is picked at death and shown as the entity's arrival
    // eye; the player lies where it died, at rest, until it is put there.
    constexpr int kDelay = 4;
    DyingPlayer dying(kDelay);
    GameWorld& world = *dying.world;
    const std::uint32_t id = dying.id;
    const glm::vec3 pit = dying.pit;
    world.step(1.0f / 30.0f);
    const Entity* e = world.find(id);
    ASSERT_NE(e, nullptr);
    EXPECT_FALSE(e->teleported);
    ASSERT_TRUE(e->respawn.has_value());
    const glm::vec3 died_at = e->move.position;
    const glm::vec3 arrival = e->respawn->arrival.position;
    EXPECT_LT(glm::length(died_at - pit), 80.0f);
    EXPECT_GT(glm::length(arrival - pit), 150.0f);
    const glm::vec3 arrival_eye = arrival + glm::vec3(0.0f, 0.0f, world.move_config().eye_height);
    for (int step = 1; step <= kDelay; ++step) {
        e = world.find(id);
        EXPECT_EQ(e->move.position, died_at) << "step " << step;
        EXPECT_EQ(e->move.velocity, glm::vec3(0.0f));
        EXPECT_EQ(world.arrival_eye_of(*e), std::optional<glm::vec3>(arrival_eye));
        const std::size_t index = static_cast<std::size_t>(e - world.entities().data());
        EXPECT_EQ(world.entity(index).arrival_eye, std::optional<glm::vec3>(arrival_eye));
        world.set_player_input(id, glm::vec3(1.0f, 0.0f, 0.0f), true, 0.0f, 0.0f); // ignored
        world.step(1.0f / 30.0f);
        EXPECT_EQ(world.find(id)->teleported, step == kDelay) << "step " << step;
    }
    e = world.find(id);
    EXPECT_TRUE(e->teleported);
    EXPECT_EQ(e->move.position, arrival);
    EXPECT_FALSE(e->respawn.has_value());
    EXPECT_FALSE(world.arrival_eye_of(*e).has_value());
}

TEST(GameWorld, ShotsTakeHealthKillAndTheKilledRespawnAfterTheDelay) {
    // Players on every spawn point; a pair with nothing between them is found by the
    // same hitscan rule, and one shoots the other twice (half of its health each time).
    constexpr int kDelay = 3;
    const auto map = testing::rooms_map();
    WorldSettings settings;
    settings.bots = 0;
    settings.respawn_delay_ticks = kDelay;
    settings.shots.damage = sim::kMaxHealth / 2;
    GameWorld world(settings, map);
    for (std::size_t i = 0; i < map->spawn_points.size(); ++i) {
        world.spawn_player();
    }
    const sim::CollisionWorld walls(map->collision_brushes);
    const std::size_t count = world.entities().size();
    std::vector<visibility::Aabb> boxes;
    for (const Entity& e : world.entities()) {
        boxes.push_back(world.box_of(e));
    }
    const std::vector<std::uint8_t> alive(count, 1);
    std::optional<std::pair<std::size_t, std::size_t>> pair;
    for (std::size_t a = 0; a < count && !pair; ++a) {
        for (std::size_t b = 0; b < count && !pair; ++b) {
            const glm::vec3 eye = world.eye_of(world.entities()[a]);
            const glm::vec3 to = glm::normalize(boxes[b].center() - eye);
            if (a != b && sim::first_hit(walls, eye, to, 8192.0f, boxes, alive, a) == b) {
                pair = {a, b};
            }
        }
    }
    ASSERT_TRUE(pair) << "no two spawn points see each other";
    const std::uint32_t shooter = world.entities()[pair->first].id;
    const std::uint32_t target = world.entities()[pair->second].id;
    const auto aim = [&] {
        const glm::vec3 eye = world.eye_of(*world.find(shooter));
        const glm::vec3 d = world.box_of(*world.find(target)).center() - eye;
        const float yaw = glm::degrees(std::atan2(d.y, d.x));
        const float pitch = -glm::degrees(std::atan2(d.z, std::hypot(d.x, d.y)));
        for (const Entity& e : world.entities()) { // everyone stands still
            world.set_player_input(e.id, glm::vec3(0.0f), false, e.id == shooter ? yaw : 0.0f,
                                   e.id == shooter ? pitch : 0.0f);
        }
        world.fire(shooter);
    };
    aim();
    world.step(1.0f / 30.0f);
    EXPECT_EQ(world.find(target)->health, sim::kMaxHealth / 2);
    EXPECT_FALSE(world.find(target)->respawn.has_value());
    EXPECT_EQ(world.frags(), 0u);
    world.step(1.0f / 30.0f); // no shot: nothing changes
    EXPECT_EQ(world.find(target)->health, sim::kMaxHealth / 2);
    aim();
    world.step(1.0f / 30.0f);
    const Entity* dead = world.find(target);
    ASSERT_TRUE(dead->respawn.has_value()) << "the second hit kills";
    EXPECT_EQ(dead->health, sim::kMaxHealth) << "full again for its next life";
    EXPECT_EQ(world.frags(), 1u);
    EXPECT_EQ(world.find(shooter)->health, sim::kMaxHealth);
    const glm::vec3 arrival = dead->respawn->arrival.position;
    for (int step = 1; step < kDelay; ++step) {
        aim(); // a dead entity is not hit again (the shot may go on to one behind it)
        world.step(1.0f / 30.0f);
        EXPECT_EQ(world.find(target)->health, sim::kMaxHealth) << "step " << step;
        EXPECT_TRUE(world.find(target)->respawn.has_value()) << "step " << step;
    }
    world.step(1.0f / 30.0f);
    EXPECT_TRUE(world.find(target)->teleported);
    EXPECT_EQ(world.find(target)->move.position, arrival);
}

TEST(GameWorld, HarmlessShotsKillNobody) {
    const auto map = testing::rooms_map();
    WorldSettings settings;
    settings.bots = 20;
    settings.sounds.bot_shots_per_second = 30.0f; // every bot fires every step
    settings.shots.damage = 0;
    GameWorld world(settings, map);
    for (int step = 0; step < 300; ++step) {
        world.step(1.0f / 30.0f);
        for (const Entity& e : world.entities()) {
            ASSERT_EQ(e.health, sim::kMaxHealth) << "step " << step << " entity " << e.id;
        }
    }
    EXPECT_EQ(world.frags(), 0u);
    settings.shots.damage = sim::kMaxHealth;
    GameWorld deadly(settings, map);
    for (int step = 0; step < 300; ++step) {
        deadly.step(1.0f / 30.0f);
    }
    EXPECT_GT(deadly.frags(), 0u) << "the same bots with deadly shots kill";
}

TEST(GameWorld, MovesThroughAParallelForGiveTheSameWorldAsOneByOne) {
    // Pits under half the spawn points, so players die and respawn (the one step that
    // is not per entity); the parallel world's moves run on four threads, in blocks.
    auto map = std::make_shared<maps::Map>(*testing::rooms_map());
    WorldSettings settings;
    settings.bots = 40;
    settings.respawn_delay_ticks = 3;
    settings.shots.damage = sim::kMaxHealth / 2; // two hits kill: deaths by shots too
    GameWorld serial(settings, map);
    GameWorld parallel(settings, map);
    // After the worlds chose their spawn points (they leave out any in a hazard).
    for (std::size_t i = 0; i < map->spawn_points.size(); i += 2) {
        testing::add_pit_at_spawn(*map, i);
    }
    std::vector<std::uint32_t> players;
    for (int i = 0; i < 40; ++i) {
        players.push_back(serial.spawn_player());
        ASSERT_EQ(parallel.spawn_player(), players.back());
    }
    std::size_t parallel_calls = 0;
    const GameWorld::ParallelFor four_threads = [&](std::size_t count,
                                                    const std::function<void(std::size_t)>& body) {
        ++parallel_calls;
        std::vector<std::thread> threads;
        for (std::size_t t = 0; t < 4; ++t) {
            threads.emplace_back([&, t] {
                for (std::size_t i = t; i < count; i += 4) {
                    body(i);
                }
            });
        }
        for (auto& th : threads) {
            th.join();
        }
    };
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    int teleports = 0;
    for (int tick = 0; tick < 300; ++tick) {
        for (const std::uint32_t id : players) {
            const glm::vec3 wish(unit(rng), unit(rng), 0.0f);
            const bool jump = unit(rng) > 0.9f;
            const float yaw = unit(rng) * 180.0f;
            serial.set_player_input(id, wish, jump, yaw, 0.0f);
            parallel.set_player_input(id, wish, jump, yaw, 0.0f);
            if (unit(rng) > 0.8f) {
                serial.fire(id);
                parallel.fire(id);
            }
        }
        serial.step(1.0f / 30.0f);
        parallel.step(1.0f / 30.0f, four_threads);
        ASSERT_EQ(serial.entities().size(), parallel.entities().size());
        for (std::size_t i = 0; i < serial.entities().size(); ++i) {
            const Entity& a = serial.entities()[i];
            const Entity& b = parallel.entities()[i];
            ASSERT_EQ(a.id, b.id);
            ASSERT_TRUE(a.move.position == b.move.position && a.move.velocity == b.move.velocity &&
                        a.move.on_ground == b.move.on_ground && a.yaw_deg == b.yaw_deg &&
                        a.teleported == b.teleported && a.health == b.health &&
                        a.respawn.has_value() == b.respawn.has_value() &&
                        (!a.respawn || a.respawn->arrival.position == b.respawn->arrival.position))
                << "tick " << tick << " entity " << a.id;
            teleports += a.teleported ? 1 : 0;
            // Death, by a pit or by shots, makes the entity whole for its next life.
            ASSERT_TRUE(!a.respawn || a.health == sim::kMaxHealth)
                << "tick " << tick << " entity " << a.id << " dead with " << a.health;
        }
    }
    EXPECT_EQ(parallel_calls, 300u);
    EXPECT_GT(teleports, 10) << "the pits should have killed players and bots";
    EXPECT_EQ(serial.frags(), parallel.frags());
    EXPECT_GT(serial.frags(), 0u) << "the shots should have killed players and bots";
}

} // namespace
} // namespace dsoc::interest
