#pragma once
// Prometheus text exposition format 0.0.4 (what /metrics serves), written here rather
// than with prometheus-cpp (docs/operations.md, "Metrics", says why). Only what the
// server needs: counters, gauges and fixed-bucket histograms, with optional labels.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace dsoc::server {

/// A histogram with fixed upper bounds in seconds, suited to tick-scale durations
/// (0.1 ms .. 1 s). Not thread-safe: observe from one thread (the tick loop).
class DurationHistogram {
public:
    /// Upper bounds of the buckets, increasing; a last +Inf bucket is implied.
    static constexpr std::array<double, 13> kBounds = {
        0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.02, 0.0333, 0.05, 0.1, 0.25, 1.0};

    /// Adds one observation. Negative or NaN values count as 0.
    void observe(double seconds);

    /// Observations <= kBounds[i] (cumulative, as Prometheus wants); index
    /// kBounds.size() is the +Inf bucket (= count()).
    [[nodiscard]] std::uint64_t cumulative(std::size_t i) const;
    [[nodiscard]] std::uint64_t count() const { return count_; }
    [[nodiscard]] double sum() const { return sum_; }

private:
    std::array<std::uint64_t, kBounds.size() + 1> buckets_{}; // not cumulative
    std::uint64_t count_ = 0;
    double sum_ = 0.0;
};

/// Label name -> value, e.g. {{"reason", "too_slow"}}. Values are escaped on output.
using MetricLabels = std::vector<std::pair<std::string, std::string>>;

/// Builds one exposition. Each family is written once with its HELP and TYPE lines;
/// names must match [a-zA-Z_:][a-zA-Z0-9_:]* (the caller's contract, asserted).
class PrometheusText {
public:
    void counter(std::string_view name, std::string_view help, double value);
    void gauge(std::string_view name, std::string_view help, double value);
    /// A gauge with one labelled sample, e.g. dsoc_build_info{version="0.1.0"} 1.
    void gauge(std::string_view name, std::string_view help, const MetricLabels& labels,
               double value);
    /// One counter family with a sample per label set (e.g. disconnects by reason).
    void counter_family(std::string_view name, std::string_view help,
                        const std::vector<std::pair<MetricLabels, double>>& samples);
    void histogram(std::string_view name, std::string_view help, const DurationHistogram& h);

    [[nodiscard]] const std::string& text() const { return text_; }

private:
    void header(std::string_view name, std::string_view help, std::string_view type);
    void sample(std::string_view name, const MetricLabels& labels, double value);

    std::string text_;
};

/// The content type of the text format, for the HTTP response.
inline constexpr std::string_view kPrometheusContentType =
    "text/plain; version=0.0.4; charset=utf-8";

} // namespace dsoc::server
