#pragma once
// A load scenario: stages that set how many clients run over time (as k6's stages),
// groups of clients that share the count by weight (as Locust's user classes), each
// with its behaviour, churn and emulated network latency, and thresholds.

#include "dsoc/simclient/threshold.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::simclient {

/// Over `duration_s`, the client count goes linearly from the previous stage's target
/// (0 before the first stage) to `target`: a ramp up, a hold (same target) or a ramp
/// down. A stage of 0 s jumps.
struct Stage {
    double duration_s = 0.0; ///< [Units: s] [Limit: >= 0]
    int target = 0;          ///< [Limit: 0..100000]
};

enum class Behaviour {
    wanderer,  ///< holds a random heading 1-3 s, then picks another (the default)
    camper,    ///< stands still; now and then a short small step; the view sweeps slowly
    respawner, ///< wanders; every respawn_every_s (+-50%) leaves and reconnects as itself
    spectator, ///< stands still and watches a player it knows (ClientInput.watch), another every
               ///< 5-10 s
};

[[nodiscard]] std::string_view to_string(Behaviour behaviour);
/// false for an unknown name.
[[nodiscard]] bool behaviour_from_string(std::string_view name, Behaviour& out);

/// Faults of a UDP link, emulated in the simulated client's UDP layer on each datagram,
/// each direction: dropped, delivered twice, or held back and delivered after the next
/// one. Probabilities. [Limit: each 0..0.9]
struct DatagramFaults {
    double loss = 0.0;
    double duplicate = 0.0;
    double reorder = 0.0;
    [[nodiscard]] bool any() const { return loss > 0.0 || duplicate > 0.0 || reorder > 0.0; }
    /// The larger of each fault's two probabilities.
    [[nodiscard]] DatagramFaults worst_with(const DatagramFaults& o) const;
};

/// Latency added on the client's side of a connection: every frame (TCP) or datagram
/// (UDP) it sends waits latency (+ up to jitter) before it is written, every byte it
/// reads waits as long before it is decoded. Jitter never reorders: TCP keeps order, and
/// over UDP reordering is a fault of its own. TCP retransmits, so packet loss cannot be
/// emulated honestly over it (it would only be latency): `faults` apply over UDP only.
struct NetworkConditions {
    double latency_ms = 0.0; ///< one way, each direction [Units: ms] [Limit: 0..10000]
    double jitter_ms = 0.0;  ///< uniform extra 0..jitter per chunk [Units: ms]
    DatagramFaults faults;   ///< UDP only
    /// Whether there is a delay to emulate.
    [[nodiscard]] bool any() const { return latency_ms > 0.0 || jitter_ms > 0.0; }
};

struct ClientGroup {
    std::string name = "clients";
    Behaviour behaviour = Behaviour::wanderer;
    /// Share of each stage's target, against the other groups' weights. [Limit: > 0]
    double weight = 1.0;
    /// Sessions per second (over the group) that leave for good and are replaced by new
    /// clients (new names and client ids). [Units: 1/s] [Limit: >= 0]
    double churn_per_s = 0.0;
    /// Respawners: mean session length before leaving and reconnecting. [Units: s]
    double respawn_every_s = 10.0;
    NetworkConditions network;
};

struct Scenario {
    std::vector<Stage> stages;
    std::vector<ClientGroup> groups;
    std::vector<Threshold> thresholds;
    /// Connect (resolve, TCP, hello) must finish within this. [Units: s] [Limit: > 0]
    double connect_timeout_s = 5.0;

    /// The run's length: the stages' durations summed. [Units: s]
    [[nodiscard]] double length_s() const;
    /// The largest target of any stage.
    [[nodiscard]] int peak_target() const;
};

/// The plain flags as a scenario: one stage ramping to `clients` over `ramp_up_s`, one
/// holding until `duration_s`, one group of wanderers.
[[nodiscard]] Scenario implicit_scenario(int clients, double duration_s, double ramp_up_s);

/// The client count the stages ask for `t_s` seconds into the run: the linear ramp,
/// rounded up (so the first client of a ramp starts at once and the last leaves at its
/// end); 0 past the end.
[[nodiscard]] int target_at(const std::vector<Stage>& stages, double t_s);

/// `total` shared among the groups by weight, largest remainders first (ties: the
/// earlier group); the shares sum to `total`.
[[nodiscard]] std::vector<int> split_by_weight(int total, const std::vector<ClientGroup>& groups);

/// Checks the ranges above; returns "" or what is wrong ("stage 2: target ...").
[[nodiscard]] std::string validate(const Scenario& scenario);

} // namespace dsoc::simclient
