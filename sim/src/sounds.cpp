#include "dsoc/sim/sounds.hpp"

#include <algorithm>

namespace dsoc::sim {

float audible_range(const Audible& audible, const SoundSettings& settings) {
    if (!settings.enabled) {
        return 0.0f;
    }
    float range = 0.0f;
    if (audible.footstep_left > 0.0f) {
        range = std::max(range, settings.footstep_range);
    }
    if (audible.shot_left > 0.0f) {
        range = std::max(range, settings.shot_range);
    }
    return range;
}

void step_sounds(Audible& audible, const MoveState& state, bool alive, bool fired, float max_speed,
                 const SoundSettings& settings, float dt) {
    if (!alive) {
        audible = {};
        return;
    }
    audible.footstep_left = std::max(0.0f, audible.footstep_left - dt);
    audible.shot_left = std::max(0.0f, audible.shot_left - dt);
    const float run = settings.run_speed_fraction * max_speed;
    const float speed2 = state.velocity.x * state.velocity.x + state.velocity.y * state.velocity.y;
    if (state.on_ground && speed2 > run * run) {
        audible.footstep_left = settings.footstep_seconds;
    }
    if (fired) {
        audible.shot_left = settings.shot_seconds;
    }
}

bool bot_fires(std::uint64_t seed, std::uint32_t id, std::uint64_t step,
               const SoundSettings& settings, float dt) {
    if (!settings.enabled || settings.bot_shots_per_second <= 0.0f) {
        return false;
    }
    // splitmix64 of the three: independent of every other random stream of the world.
    std::uint64_t z = seed ^ (std::uint64_t{id} << 40) ^ (step * 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    const double chance = static_cast<double>(settings.bot_shots_per_second) * dt;
    return static_cast<double>(z >> 11) * 0x1.0p-53 < chance;
}

} // namespace dsoc::sim
