// Footing: the ledges a walker does not walk off, the spawn points it can stand at, and
// wandering bots on platforms over a void (they used to walk off and fall to the
// trigger_hurt below).

#include "dsoc/maps/map_spec.hpp"
#include "dsoc/sim/footing.hpp"
#include "dsoc/sim/wander_bot.hpp"

#include <gtest/gtest.h>

#include <string>

namespace dsoc::sim {
namespace {

constexpr float kDt = 1.0f / 30.0f;
constexpr float kMaxDrop = 512.0f;
/// A walker's origin standing on a floor whose top is at z = 0 (movement leaves it a
/// clip epsilon above, not touching).
constexpr float kStandingZ = 24.0f + kSurfaceClipEpsilon;
const glm::vec3 kEast{1.0f, 0.0f, 0.0f};
constexpr float kSpeed = 320.0f; ///< off an edge at full speed [Units: world units/s]

maps::Map text_map(const std::string& boxes) {
    auto spec = maps::parse_text_map("dsoc-map 1\n" + boxes, "footing");
    EXPECT_TRUE(spec.ok()) << spec.error().message();
    return maps::build_map(spec.value(), "footing");
}

/// A 512-unit platform (top at z = 0, edge at x = 256) over a void with a kill volume
/// far below, plus `more`.
maps::Map platform(const std::string& more = "") {
    return text_map("box solid -256 -256 -16 256 256 0\n"
                    "hazard -4096 -4096 -3000 4096 4096 -2990\n"
                    "spawn 0 0 25\n" +
                    more);
}

bool unsafe(const maps::Map& map, float x, glm::vec3 direction = kEast, float lookahead = 64.0f) {
    const CollisionWorld world(map.collision_brushes);
    return unsafe_ledge_ahead(world, MoveConfig{}, {x, 0.0f, kStandingZ}, direction, kSpeed,
                              lookahead, kMaxDrop, map.hazards);
}

TEST(Footing, AnEdgeOverTheVoidIsALedgeAndTheMiddleOfTheFloorIsNot) {
    const maps::Map map = platform();
    EXPECT_FALSE(unsafe(map, 0.0f));
    EXPECT_FALSE(unsafe(map, 150.0f)); // the box still overlaps the floor 64 units on
    EXPECT_TRUE(unsafe(map, 220.0f));
    EXPECT_TRUE(unsafe(map, 250.0f));
    EXPECT_FALSE(unsafe(map, 220.0f, -kEast)); // walking back in is fine
}

TEST(Footing, ALedgeUnderALowCeilingIsFound) {
    // 10 units above the standing box: a step's height above it is in the ceiling.
    EXPECT_TRUE(unsafe(platform("box solid -256 -256 66 256 256 80\n"), 220.0f));
}

TEST(Footing, AStepDownWithinTheSafeDropIsNotALedgeAndADeeperOneIs) {
    EXPECT_FALSE(unsafe(platform("box solid 256 -256 -216 768 256 -200\n"), 220.0f));
    EXPECT_TRUE(unsafe(platform("box solid 256 -256 -616 768 256 -600\n"), 220.0f));
}

TEST(Footing, ANarrowLedgeBelowThatTheFallOvershootsIsALedge) {
    // A 48-unit ledge 200 units down: at full speed the walker comes down about 220 units
    // further on, over the void; at a walk it lands on the ledge.
    const maps::Map map = platform("box solid 256 -256 -216 304 256 -200\n");
    EXPECT_TRUE(unsafe(map, 220.0f));
    const CollisionWorld world(map.collision_brushes);
    EXPECT_FALSE(unsafe_ledge_ahead(world, MoveConfig{}, {220.0f, 0.0f, kStandingZ}, kEast, 10.0f,
                                    64.0f, kMaxDrop, map.hazards));
}

TEST(Footing, ADropIntoAHazardIsALedge) {
    const std::string lower = "box solid 256 -256 -216 768 256 -200\n";
    EXPECT_FALSE(unsafe(platform(lower), 220.0f));
    EXPECT_TRUE(unsafe(platform(lower + "hazard 256 -256 -200 768 256 -190\n"), 220.0f));
}

TEST(Footing, AGapTheBoxFitsIntoIsFoundThoughFloorLiesBeyondIt) {
    // 44 units of void, then floor again: a probe only at the far end stands on it.
    const maps::Map map = platform("box solid 300 -256 -16 812 256 0\n");
    EXPECT_TRUE(unsafe(map, 230.0f));
    // A probe only at the far end (one box width past the edge) stands on the floor beyond.
    const CollisionWorld world(map.collision_brushes);
    EXPECT_FALSE(unsafe_ledge_ahead(world, MoveConfig{}, {294.0f, 0.0f, kStandingZ}, kEast, kSpeed,
                                    0.001f, kMaxDrop, map.hazards));
}

TEST(Footing, AWallAheadIsNotALedge) {
    EXPECT_FALSE(unsafe(platform("box solid 200 -256 0 232 256 256\n"), 150.0f));
}

TEST(Footing, SpawnPointsOverTheVoidAreLeftOut) {
    const maps::Map map = platform("spawn 1000 0 25\n");
    const CollisionWorld world(map.collision_brushes);
    const auto usable =
        spawn_points_with_footing(world, MoveConfig{}, map.spawn_points, kMaxDrop, map.hazards);
    ASSERT_EQ(map.spawn_points.size(), 2u);
    ASSERT_EQ(usable.size(), 1u);
    EXPECT_EQ(usable[0].origin, map.spawn_points[0].origin);

    // With no spawn point on a floor, all of them (a map is still playable somehow).
    const maps::Map all_void = text_map("box solid -256 -256 -16 256 256 0\n"
                                        "spawn 1000 0 25\nspawn 2000 0 25\n");
    const CollisionWorld void_world(all_void.collision_brushes);
    EXPECT_EQ(spawn_points_with_footing(void_world, MoveConfig{}, all_void.spawn_points, kMaxDrop,
                                        all_void.hazards)
                  .size(),
              2u);
}

/// Two platforms 256 units apart over a void, a spawn point on each: every bot's goals
/// lie across the gap half the time.
std::uint32_t deaths_of_bots_between_two_platforms(const WanderConfig& wander) {
    const maps::Map map = text_map("box solid -512 -256 -16 0 256 0\n"
                                   "box solid 256 -256 -16 768 256 0\n"
                                   "hazard -4096 -4096 -3000 4096 4096 -2990\n"
                                   "spawn -256 0 25\nspawn 512 0 25\n");
    const CollisionWorld world(map.collision_brushes);
    const MoveConfig move;
    auto bots = spawn_wander_bots(world, move, map.spawn_points, 20, 7);
    std::uint32_t deaths = 0;
    for (int tick = 0; tick < 60 * 30; ++tick) {
        for (WanderBot& bot : bots) {
            wander_step(bot, world, wander, move, map.spawn_points, map.hazards, kDt);
        }
    }
    std::uint32_t avoided = 0;
    for (const WanderBot& bot : bots) {
        deaths += bot.deaths;
        avoided += bot.ledges_avoided;
    }
    if (wander.max_safe_drop > 0.0f) {
        EXPECT_GT(avoided, 0u); // they did come to the edge
    }
    return deaths;
}

TEST(WanderFooting, BotsStayOnTheirPlatformsOverAVoid) {
    EXPECT_EQ(deaths_of_bots_between_two_platforms(WanderConfig{}), 0u);
    WanderConfig walks_off_anything;
    walks_off_anything.max_safe_drop = 0.0f;
    EXPECT_GT(deaths_of_bots_between_two_platforms(walks_off_anything), 10u);
}

} // namespace
} // namespace dsoc::sim
