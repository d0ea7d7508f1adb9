#pragma once
// What dsoc-eval measures per policy (docs/evaluation.md defines each figure).

#include "dsoc/eval/policies.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace dsoc::eval {

/// One concrete pop-in violation, for bug reports.
struct ViolationExample {
    std::uint64_t tick = 0;
    std::uint32_t client = 0;
    std::uint32_t entity = 0;
    bool present_eye = false; ///< visible from the eye at t itself (else only within t..t+K)
};

struct PolicyMetrics {
    std::string name;
    int lookahead_ticks = 0;

    // Traffic, every tick and client.
    std::uint64_t client_ticks = 0;
    std::uint64_t enters = 0;
    std::uint64_t updates = 0;
    std::uint64_t leaves = 0;
    std::uint64_t bytes = 0;
    std::uint64_t replicated_pairs = 0; ///< sum over client-ticks of the set size
    // Hearing (Scenario::sounds), every tick and client.
    std::uint64_t heard_pairs = 0;   ///< of replicated_pairs, sent only because heard
    std::uint64_t heard_entries = 0; ///< enters and updates on the heard tier
    /// The bytes the same sets without the heard-only entities would have cost (only
    /// with sounds; 0 without): `bytes` minus this is what hearing adds.
    std::uint64_t sight_bytes = 0;

    // CPU: per client-tick decision time (thread CPU time; the serial part of a tick
    // is shared equally among the clients). [Units: microseconds]
    std::vector<float> cpu_us;

    // Oracle-checked client-ticks.
    std::uint64_t checked_client_ticks = 0;
    std::uint64_t checked_replicated = 0; ///< replicated triples on checked ticks
    std::uint64_t exposed = 0;            ///< replicated, not visible within the allowance
    std::uint64_t popin_present = 0;      ///< visible from the present eye, not replicated
    std::uint64_t popin_lookahead = 0;    ///< visible from an eye in t..t+K, not replicated
    /// Pairs a rule other than sight decides (teammates), on checked ticks: left out of
    /// exposure and pop-in; `missed_by_rule` of them were not sent (must be 0).
    std::uint64_t checked_by_rule = 0;
    std::uint64_t missed_by_rule = 0;
    /// Heard-only pairs on checked ticks: not sent for sight, so left out of exposure
    /// (this is hearing's exposure, at its coarse precision); `heard_visible` of them were
    /// visible within the allowance and so are pop-in too (sight needed them precise).
    std::uint64_t checked_heard = 0;
    std::uint64_t heard_visible = 0;
    std::vector<ViolationExample> examples; ///< the first few

    // Bytes on the ticks where the ideal's bytes are known (see EvalResult).
    std::uint64_t measured_bytes = 0;

    TbvSummary tbv;
    std::uint64_t live_tbv_sum = 0; ///< live TBV groups summed over clients, per checked tick
    std::uint64_t live_tbv_samples = 0;
};

struct Percentiles {
    double mean = 0.0;
    double p99 = 0.0;
    double max = 0.0;
};
[[nodiscard]] Percentiles summarize(std::vector<float> values);

} // namespace dsoc::eval
