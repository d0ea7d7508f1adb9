#include "dsoc/server/metrics.hpp"

#include <fmt/format.h>

#include <cassert>
#include <cmath>

namespace dsoc::server {

namespace {

[[maybe_unused]] bool valid_name(std::string_view name) {
    if (name.empty()) {
        return false;
    }
    for (std::size_t i = 0; i < name.size(); ++i) {
        const char c = name[i];
        const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':';
        if (!alpha && !(i > 0 && c >= '0' && c <= '9')) {
            return false;
        }
    }
    return true;
}

/// Escapes a label value (\\, \" and \n) or HELP text (\\ and \n).
std::string escape(std::string_view text, bool quote) {
    std::string out;
    for (const char c : text) {
        if (c == '\\') {
            out += "\\\\";
        } else if (c == '\n') {
            out += "\\n";
        } else if (c == '"' && quote) {
            out += "\\\"";
        } else {
            out += c;
        }
    }
    return out;
}

std::string number(double v) {
    if (std::isnan(v)) {
        return "NaN";
    }
    if (std::isinf(v)) {
        return v > 0 ? "+Inf" : "-Inf";
    }
    return fmt::format("{}", v); // shortest round-trip form
}

} // namespace

void DurationHistogram::observe(double seconds) {
    if (!(seconds > 0.0)) {
        seconds = 0.0;
    }
    std::size_t i = 0;
    while (i < kBounds.size() && seconds > kBounds[i]) {
        ++i;
    }
    ++buckets_[i];
    ++count_;
    sum_ += seconds;
}

std::uint64_t DurationHistogram::cumulative(std::size_t i) const {
    std::uint64_t total = 0;
    for (std::size_t k = 0; k <= i && k < buckets_.size(); ++k) {
        total += buckets_[k];
    }
    return total;
}

void PrometheusText::header(std::string_view name, std::string_view help, std::string_view type) {
    assert(valid_name(name));
    text_ += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, escape(help, false), name, type);
}

void PrometheusText::sample(std::string_view name, const MetricLabels& labels, double value) {
    text_ += name;
    if (!labels.empty()) {
        text_ += '{';
        for (std::size_t i = 0; i < labels.size(); ++i) {
            assert(valid_name(labels[i].first));
            text_ += fmt::format("{}{}=\"{}\"", i > 0 ? "," : "", labels[i].first,
                                 escape(labels[i].second, true));
        }
        text_ += '}';
    }
    text_ += ' ';
    text_ += number(value);
    text_ += '\n';
}

void PrometheusText::counter(std::string_view name, std::string_view help, double value) {
    header(name, help, "counter");
    sample(name, {}, value);
}

void PrometheusText::gauge(std::string_view name, std::string_view help, double value) {
    header(name, help, "gauge");
    sample(name, {}, value);
}

void PrometheusText::gauge(std::string_view name, std::string_view help, const MetricLabels& labels,
                           double value) {
    header(name, help, "gauge");
    sample(name, labels, value);
}

void PrometheusText::counter_family(std::string_view name, std::string_view help,
                                    const std::vector<std::pair<MetricLabels, double>>& samples) {
    header(name, help, "counter");
    for (const auto& [labels, value] : samples) {
        sample(name, labels, value);
    }
}

void PrometheusText::histogram(std::string_view name, std::string_view help,
                               const DurationHistogram& h) {
    header(name, help, "histogram");
    const std::string bucket = std::string(name) + "_bucket";
    for (std::size_t i = 0; i < DurationHistogram::kBounds.size(); ++i) {
        sample(bucket, {{"le", number(DurationHistogram::kBounds[i])}},
               static_cast<double>(h.cumulative(i)));
    }
    sample(bucket, {{"le", "+Inf"}}, static_cast<double>(h.count()));
    sample(std::string(name) + "_sum", {}, h.sum());
    sample(std::string(name) + "_count", {}, static_cast<double>(h.count()));
}

} // namespace dsoc::server
