#pragma once
// The figures of a load report a threshold may name: each with its dimension (which
// fixes its units) and how to read it from a LoadReport.

#include "dsoc/simclient/quantity.hpp"

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::simclient {

struct LoadReport;

/// A figure's value in a report; `present` is false when it has no samples.
struct FigureValue {
    double value = 0.0; ///< in the dimension's base unit
    bool present = true;
};

struct Figure {
    std::string name;
    Dimension dimension;
    std::string meaning;
    std::function<FigureValue(const LoadReport&)> read;
};

/// Every figure, in a fixed order (the order of docs/simclient.md's table).
[[nodiscard]] const std::vector<Figure>& report_figures();

/// The figure named `name`, or nullptr.
[[nodiscard]] const Figure* find_figure(std::string_view name);

/// "interarrival_mean, interarrival_p50, ...": every figure's name, for messages.
[[nodiscard]] std::string figure_names();

} // namespace dsoc::simclient
