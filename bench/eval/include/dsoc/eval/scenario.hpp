#pragma once
// Named evaluation scenarios (bench/scenarios.json): which map, how many walking
// viewers and bots, tick rate, latency and duration.

#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::eval {

struct Scenario {
    std::string name = "custom";
    std::string description;
    /// Map spec for dsoc::maps::load_map ("oa_dm4", "gen:city", "gen:rooms", a path).
    std::string map = "oa_dm4";
    /// For "gen:city": blocks per side (0: the generator's default). [Limit: 0..256]
    int city_blocks = 0;
    /// Walking players the server replicates to; each is also an entity. [Limit: >= 1]
    int viewers = 64;
    /// Wandering bots. [Limit: >= 0]
    int bots = 512;
    /// Teams (0: none): entity i (viewers first, then bots) plays for team i % teams + 1,
    /// and every policy sends a viewer its teammates whatever it sees; the oracle judges
    /// only the other pairs. [Limit: 0..1000]
    int teams = 0;
    /// Footsteps and shots (sim::SoundSettings, its defaults): every policy sends what a
    /// viewer hears but does not see on the heard tier (interest::Hearing); the oracle
    /// judges sight alone and counts the heard-only pairs apart.
    bool sounds = false;
    /// [Units: Hz] [Limit: 1..240]
    int tick_rate = 30;
    /// Client round trip. [Units: ms] [Limit: >= 0]
    int rtt_ms = 100;
    /// Client entity-interpolation delay. [Units: ms] [Limit: >= 0]
    int interpolation_ms = 50;
    /// Simulated time. [Units: s] [Limit: > 0]
    double duration_s = 60.0;
    /// The oracle checks every this many ticks (plus the tick before each, which the
    /// ideal's byte count needs). 1 = every tick. [Units: ticks] [Limit: >= 1]
    int oracle_every = 15;
    /// The oracle judges at most this many clients per judged tick: every
    /// ceil(viewers / oracle_clients)-th client, the same ones all run (0 = all).
    /// [Limit: >= 0]
    int oracle_clients = 0;
    /// Policies run when the command line names none (empty: all).
    std::vector<std::string> policies;
    /// Radius of the `distance` policy. [Units: world units] [Limit: > 0]
    float distance_radius = 1500.0f;
    /// Bots, viewers and spawn choices. Same seed, same motion.
    std::uint64_t seed = 1;

    /// Latency allowance in ticks: rtt + interpolation in whole ticks, rounded up
    /// (interest::lookahead_ticks(), the server's rule).
    [[nodiscard]] int lookahead_ticks() const;
    /// Every how many clients the oracle judges one.
    [[nodiscard]] int oracle_client_stride() const {
        return oracle_clients <= 0 || oracle_clients >= viewers
                   ? 1
                   : (viewers + oracle_clients - 1) / oracle_clients;
    }
    [[nodiscard]] int total_ticks() const { return static_cast<int>(duration_s * tick_rate + 0.5); }
};

/// Every problem with the scenario, in words; empty when usable.
[[nodiscard]] std::vector<std::string> validate(const Scenario& s);

/// Reads every scenario of a scenarios file. False with `error` set on failure.
[[nodiscard]] bool load_scenarios(const std::string& path, std::vector<Scenario>& out,
                                  std::string& error);

/// The scenarios file: $DSOC_SCENARIOS when set, else bench/scenarios.json of the
/// source tree dsoc-eval was built from.
[[nodiscard]] std::string default_scenarios_path();

} // namespace dsoc::eval
