#pragma once
// The sounds a walking entity makes, as interest management needs them: how far each
// is heard and for how long. Sound travels in a straight line and walls do not stop
// it, as in Quake 3's mixer, which fades every sound by its distance alone to silence
// at about 1,330 units (full volume within 80, then 0.0008 of it less per unit) and
// draws no occlusion. An entity sounding with range R is heard by every client whose
// eye is within R of its box (interest/hearing.hpp), for as long as it sounds.
//
// Footsteps: while the entity runs on the ground (faster than a walk); they fade
// footstep_seconds after the last running step. Shots: when it fires (a player's
// input, a bot's own dice), heard for shot_seconds. A dead entity makes none.

#include "dsoc/sim/player_move.hpp"

#include <cstdint>

namespace dsoc::sim {

struct SoundSettings {
    /// Whether entities make sounds at all (false: every range is 0).
    bool enabled = true;
    /// How far footsteps are heard (0: never). [Units: world units] [Limit: >= 0]
    float footstep_range = 800.0f;
    /// How long a footstep is heard after the last running step. [Units: s] [Limit: >= 0]
    float footstep_seconds = 0.3f;
    /// Footsteps above this share of the speed bound (a walk is half of it in Quake 3,
    /// and silent). [Limit: 0..1]
    float run_speed_fraction = 0.6f;
    /// How far a shot is heard (0: never). [Units: world units] [Limit: >= 0]
    float shot_range = 1330.0f;
    /// How long a shot is heard. [Units: s] [Limit: >= 0]
    float shot_seconds = 0.5f;
    /// How often a living bot fires, on average (a Poisson rate). [Units: 1/s] [Limit: >= 0]
    float bot_shots_per_second = 0.25f;
};

/// The sounds one entity is making: the time each has left. [Units: s]
struct Audible {
    float footstep_left = 0.0f;
    float shot_left = 0.0f;
};

/// How far the entity is heard now: the range of the loudest sound it is making, 0
/// when silent. [Units: world units]
[[nodiscard]] float audible_range(const Audible& audible, const SoundSettings& settings);

/// One world step of `dt` seconds for an entity in `state` (after its move): counts the
/// sounds down, starts footsteps when it runs on the ground faster than
/// run_speed_fraction * max_speed, and a shot when `fired`. `alive` false silences it.
void step_sounds(Audible& audible, const MoveState& state, bool alive, bool fired, float max_speed,
                 const SoundSettings& settings, float dt);

/// Whether bot `id` fires in world step `step`: a draw from (seed, id, step) alone, so
/// it neither depends on nor disturbs the bots' movement streams, at
/// bot_shots_per_second on average.
[[nodiscard]] bool bot_fires(std::uint64_t seed, std::uint32_t id, std::uint64_t step,
                             const SoundSettings& settings, float dt);

} // namespace dsoc::sim
