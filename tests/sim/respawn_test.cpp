// Respawns decided ahead of time (sim/respawn.hpp): a wandering bot that dies is put
// at the spawn point picked at its death, exactly respawn_delay_ticks steps later, and
// lies where it died, at rest, until then.

#include "dsoc/maps/map_source.hpp"
#include "dsoc/sim/wander_bot.hpp"
#include "support/openarena.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

namespace dsoc::sim {
namespace {

constexpr float kDt = 1.0f / 30.0f;
constexpr int kDelay = 5;

/// What happened to one bot around its first death.
struct FirstDeath {
    int step = -1;         ///< the step it died in (-1: never)
    int respawn_step = -1; ///< the step it was put at its spawn point
    glm::vec3 arrival{0.0f};
};

std::vector<FirstDeath> first_deaths(const maps::Map& map, int delay, std::size_t bots, int steps) {
    const CollisionWorld world(map.collision_brushes);
    const MoveConfig move;
    WanderConfig wander;
    wander.respawn_delay_ticks = delay;
    std::vector<WanderBot> all = spawn_wander_bots(world, move, map.spawn_points, bots, 7);
    std::vector<FirstDeath> deaths(bots);
    std::vector<glm::vec3> died_at(bots);
    for (int step = 0; step < steps; ++step) {
        for (std::size_t i = 0; i < all.size(); ++i) {
            WanderBot& bot = all[i];
            const bool was_dead = bot.respawn.has_value();
            wander_step(bot, world, wander, move, map.spawn_points, map.hazards, kDt);
            FirstDeath& d = deaths[i];
            if (d.respawn_step >= 0) {
                continue; // only the first death is followed
            }
            if (delay == 0) {
                EXPECT_FALSE(bot.respawn.has_value()) << "bot " << i << " step " << step;
                if (bot.respawned) {
                    d = {step, step, bot.state.position};
                }
                continue;
            }
            if (!was_dead && bot.respawn) { // it died in this step
                EXPECT_FALSE(bot.respawned);
                EXPECT_EQ(bot.respawn->ticks_left, delay) << "bot " << i;
                EXPECT_EQ(bot.state.velocity, glm::vec3(0.0f));
                d.step = step;
                d.arrival = bot.respawn->arrival.position;
                died_at[i] = bot.state.position;
            } else if (was_dead && bot.respawn) { // lying where it died, at rest
                EXPECT_FALSE(bot.respawned);
                EXPECT_EQ(bot.state.position, died_at[i]) << "bot " << i << " step " << step;
                EXPECT_EQ(bot.state.velocity, glm::vec3(0.0f));
                EXPECT_EQ(bot.respawn->arrival.position, d.arrival);
            } else if (was_dead) { // put at its spawn point
                EXPECT_TRUE(bot.respawned);
                EXPECT_EQ(bot.state.position, d.arrival) << "bot " << i;
                d.respawn_step = step;
            } else {
                EXPECT_FALSE(bot.respawned) << "bot " << i << " step " << step;
            }
        }
    }
    return deaths;
}

TEST(Respawn, ABotIsPutAtTheSpawnPointPickedAtItsDeathExactlyTheDelayLater) {
    DSOC_REQUIRE_OPENARENA();
    // oa_dm4 has lava and pits that wandering bots walk into.
    const auto map = maps::load_map("oa_dm4", maps::MapSearch{{testing::kOpenArenaPak}});
    ASSERT_TRUE(map) << map.error().message();
    ASSERT_FALSE(map->hazards.empty());
    constexpr std::size_t kBots = 100;
    constexpr int kSteps = 40 * 30;
    const std::vector<FirstDeath> delayed = first_deaths(map.value(), kDelay, kBots, kSteps);
    const std::vector<FirstDeath> at_once = first_deaths(map.value(), 0, kBots, kSteps);
    int respawns = 0;
    for (std::size_t i = 0; i < kBots; ++i) {
        if (delayed[i].respawn_step < 0) {
            continue;
        }
        ++respawns;
        EXPECT_EQ(delayed[i].respawn_step - delayed[i].step, kDelay) << "bot " << i;
        // Each bot draws from its own random stream, and nothing is drawn while it is
        // dead: until its first death it walks as without a delay, and dies at the same
        // step, bound for the same spawn point.
        EXPECT_EQ(delayed[i].step, at_once[i].step) << "bot " << i;
        EXPECT_EQ(delayed[i].arrival, at_once[i].arrival) << "bot " << i;
    }
    EXPECT_GE(respawns, 5) << "too few deaths to show anything";
}

} // namespace
} // namespace dsoc::sim
