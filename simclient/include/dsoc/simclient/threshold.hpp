#pragma once
// Thresholds, as k6 has them: a condition on a figure of the report
// ("interarrival_p99 < 50ms") that fails the run when it does not hold.

#include "dsoc/simclient/quantity.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace dsoc::simclient {

struct LoadReport;

enum class Comparison { less, less_equal, greater, greater_equal };

/// "<", "<=", ">", ">=".
[[nodiscard]] std::string_view to_string(Comparison comparison);

/// One condition: `figure` `comparison` `limit`.
struct Threshold {
    std::string text;   ///< as written, spaces removed ("interarrival_p99<50ms")
    std::string figure; ///< a name of report_figures()
    Comparison comparison = Comparison::less;
    Quantity limit;         ///< in the figure's base unit, with the unit it was written in
    std::string limit_text; ///< the limit as written ("50ms")
};

/// Parses "FIGURE OP VALUE[UNIT]" (spaces anywhere). Returns false with `error` when
/// the figure is unknown (the error lists the known ones), the operator is not one of
/// < <= > >=, or the value is not a quantity of the figure's dimension.
[[nodiscard]] bool parse_threshold(std::string_view text, Threshold& out, std::string& error);

/// A threshold checked against a finished run.
struct ThresholdResult {
    Threshold threshold;
    bool passed = false;
    /// False when the figure has no samples (e.g. rtt_p99 without a pong): the
    /// threshold then fails, since nothing shows it holds.
    bool has_value = false;
    double observed = 0.0; ///< in the figure's base unit
};

[[nodiscard]] std::vector<ThresholdResult> evaluate_thresholds(const std::vector<Threshold>& all,
                                                               const LoadReport& report);

/// "interarrival_p99 < 50ms: observed 61.3 ms" (the observed value in the limit's unit).
[[nodiscard]] std::string describe(const ThresholdResult& result);

} // namespace dsoc::simclient
