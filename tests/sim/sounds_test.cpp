// The sounds a walking entity makes (sim/sounds.hpp): footsteps while it runs on the
// ground and not while it walks, jumps or lies dead; a shot for shot_seconds; each fades
// on time; bots fire at the configured rate from a stream of their own.

#include "dsoc/sim/sounds.hpp"

#include <gtest/gtest.h>

namespace dsoc::sim {
namespace {

constexpr float kMaxSpeed = 320.0f;
constexpr float kDt = 1.0f / 30.0f;

MoveState moving(float speed, bool on_ground) {
    MoveState s;
    s.velocity = {speed, 0.0f, 0.0f};
    s.on_ground = on_ground;
    return s;
}

TEST(Sounds, FootstepsWhileRunningOnTheGroundOnlyAndTheyFadeOnTime) {
    const SoundSettings settings;
    Audible a;
    step_sounds(a, moving(0.4f * kMaxSpeed, true), true, false, kMaxSpeed, settings, kDt);
    EXPECT_EQ(audible_range(a, settings), 0.0f) << "a walk is silent";
    step_sounds(a, moving(kMaxSpeed, false), true, false, kMaxSpeed, settings, kDt);
    EXPECT_EQ(audible_range(a, settings), 0.0f) << "in the air: no footsteps";
    step_sounds(a, moving(kMaxSpeed, true), true, false, kMaxSpeed, settings, kDt);
    EXPECT_EQ(audible_range(a, settings), settings.footstep_range);
    // Standing still from now on: heard for footstep_seconds, then not.
    int heard_steps = 0;
    for (int i = 0; i < 60; ++i) {
        step_sounds(a, moving(0.0f, true), true, false, kMaxSpeed, settings, kDt);
        heard_steps += audible_range(a, settings) > 0.0f ? 1 : 0;
    }
    EXPECT_NEAR(heard_steps * kDt, settings.footstep_seconds, 1.5f * kDt);
}

TEST(Sounds, AShotIsTheLoudestSoundForShotSecondsAndTheDeadAreSilent) {
    const SoundSettings settings;
    Audible a;
    step_sounds(a, moving(kMaxSpeed, true), true, true, kMaxSpeed, settings, kDt);
    EXPECT_EQ(audible_range(a, settings), settings.shot_range);
    int shot_steps = 1;
    for (int i = 0; i < 60 && audible_range(a, settings) == settings.shot_range; ++i) {
        step_sounds(a, moving(0.0f, true), true, false, kMaxSpeed, settings, kDt);
        shot_steps += audible_range(a, settings) == settings.shot_range ? 1 : 0;
    }
    EXPECT_NEAR(shot_steps * kDt, settings.shot_seconds, 1.5f * kDt);
    step_sounds(a, moving(kMaxSpeed, true), true, true, kMaxSpeed, settings, kDt);
    step_sounds(a, moving(kMaxSpeed, true), false, true, kMaxSpeed, settings, kDt);
    EXPECT_EQ(audible_range(a, settings), 0.0f) << "dead";
    SoundSettings off = settings;
    off.enabled = false;
    step_sounds(a, moving(kMaxSpeed, true), true, true, kMaxSpeed, off, kDt);
    EXPECT_EQ(audible_range(a, off), 0.0f) << "sounds off";
}

TEST(Sounds, BotsFireAtTheirRateFromAStreamOfTheirOwn) {
    SoundSettings settings;
    settings.bot_shots_per_second = 0.5f;
    int shots = 0;
    constexpr int kBots = 100;
    constexpr int kSteps = 3000; // 100 s at 30 Hz each
    for (std::uint32_t id = 1; id <= kBots; ++id) {
        for (std::uint64_t step = 0; step < kSteps; ++step) {
            shots += bot_fires(7, id, step, settings, kDt) ? 1 : 0;
        }
    }
    const double expected = 0.5 * kBots * kSteps * kDt; // 5,000
    EXPECT_NEAR(shots, expected, 0.05 * expected);
    EXPECT_EQ(bot_fires(7, 3, 11, settings, kDt), bot_fires(7, 3, 11, settings, kDt));
    settings.enabled = false;
    EXPECT_FALSE(bot_fires(7, 3, 11, settings, 1.0f));
}

} // namespace
} // namespace dsoc::sim
