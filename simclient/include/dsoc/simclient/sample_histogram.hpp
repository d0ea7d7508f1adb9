#pragma once
// Fixed-precision histogram of non-negative samples (latencies, counts) for the
// load report: memory does not grow with the run's length, unlike a vector of every
// sample (500 clients x 30 snapshots/s x 10 min is 9 M samples per statistic).
//
// Precision: 64 buckets per power of two, so a percentile is reported within 0.8%
// (relative) of the sample at that rank; count, mean and max are exact. Samples
// below 2^-10 (about 0.001) count as 0; samples above 2^30 (about 1.07e9) fall in
// the last bucket (percentiles there are clamped to the exact maximum). Negative and
// non-finite samples are ignored. Memory: 8 bytes per bucket up to the largest
// sample's: 10 KiB for samples below 1000.
//
// Threading: none; one per client, merged for the report.

#include "dsoc/common/percentiles.hpp"

#include <cstdint>
#include <vector>

namespace dsoc::simclient {

class SampleHistogram {
public:
    void add(double value);
    /// Adds every sample of `other`.
    void merge(const SampleHistogram& other);
    [[nodiscard]] std::uint64_t count() const { return count_; }
    /// count, exact mean and max; p50/p95/p99 as nearest-rank percentiles within the
    /// precision above.
    [[nodiscard]] common::Summary summary() const;

private:
    std::vector<std::uint64_t> buckets_; // index 0: zero (and below 2^-10)
    std::uint64_t count_ = 0;
    double sum_ = 0.0;
    double max_ = 0.0;
};

} // namespace dsoc::simclient
