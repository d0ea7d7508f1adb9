#include "dsoc/simclient/threshold.hpp"

#include "dsoc/simclient/load_report.hpp"
#include "dsoc/simclient/report_figures.hpp"

#include <fmt/format.h>

#include <cctype>

namespace dsoc::simclient {

std::string_view to_string(Comparison comparison) {
    switch (comparison) {
    case Comparison::less:
        return "<";
    case Comparison::less_equal:
        return "<=";
    case Comparison::greater:
        return ">";
    case Comparison::greater_equal:
        return ">=";
    }
    return "?";
}

bool parse_threshold(std::string_view text, Threshold& out, std::string& error) {
    std::string compact;
    for (const char c : text) {
        if (std::isspace(static_cast<unsigned char>(c)) == 0) {
            compact += c;
        }
    }
    const auto op_at = compact.find_first_of("<>=!");
    if (op_at == std::string::npos || op_at == 0) {
        error = "threshold '" + std::string(text) +
                "': expected FIGURE OP VALUE, e.g. interarrival_p99<50ms (OP: < <= > >=)";
        return false;
    }
    Threshold t;
    t.text = compact;
    t.figure = compact.substr(0, op_at);
    std::size_t value_at = op_at + 1;
    const char first = compact[op_at];
    const bool or_equal = value_at < compact.size() && compact[value_at] == '=';
    if (first == '<') {
        t.comparison = or_equal ? Comparison::less_equal : Comparison::less;
    } else if (first == '>') {
        t.comparison = or_equal ? Comparison::greater_equal : Comparison::greater;
    } else {
        error = "threshold '" + std::string(text) + "': unknown operator; use < <= > >=";
        return false;
    }
    value_at += or_equal ? 1 : 0;
    const Figure* figure = find_figure(t.figure);
    if (figure == nullptr) {
        error = "threshold '" + std::string(text) + "': unknown figure '" + t.figure +
                "'; known: " + figure_names();
        return false;
    }
    const std::string value = compact.substr(value_at);
    if (value.find_first_of("<>=") != std::string::npos) {
        error = "threshold '" + std::string(text) + "': unknown operator; use < <= > >=";
        return false;
    }
    std::string why;
    if (!parse_quantity(value, figure->dimension, t.limit, why)) {
        error = "threshold '" + std::string(text) + "': " + t.figure + ": " + why;
        return false;
    }
    t.limit_text = value;
    out = std::move(t);
    return true;
}

std::vector<ThresholdResult> evaluate_thresholds(const std::vector<Threshold>& all,
                                                 const LoadReport& report) {
    std::vector<ThresholdResult> results;
    results.reserve(all.size());
    for (const Threshold& t : all) {
        ThresholdResult r;
        r.threshold = t;
        const Figure* figure = find_figure(t.figure);
        if (figure != nullptr) {
            const FigureValue v = figure->read(report);
            r.has_value = v.present;
            r.observed = v.value;
        }
        const double limit = t.limit.base;
        switch (t.comparison) {
        case Comparison::less:
            r.passed = r.observed < limit;
            break;
        case Comparison::less_equal:
            r.passed = r.observed <= limit;
            break;
        case Comparison::greater:
            r.passed = r.observed > limit;
            break;
        case Comparison::greater_equal:
            r.passed = r.observed >= limit;
            break;
        }
        r.passed = r.passed && r.has_value;
        results.push_back(std::move(r));
    }
    return results;
}

std::string describe(const ThresholdResult& result) {
    const Threshold& t = result.threshold;
    const std::string condition =
        fmt::format("{} {} {}", t.figure, to_string(t.comparison), t.limit_text);
    if (!result.has_value) {
        return condition + ": no samples";
    }
    const std::string unit = t.limit.unit.empty() ? "" : " " + t.limit.unit;
    return fmt::format("{}: observed {:.4g}{}", condition, result.observed / t.limit.per_unit,
                       unit);
}

} // namespace dsoc::simclient
