#include "dsoc/simclient/sample_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::simclient {

namespace {

constexpr int kSubBuckets = 64; // per power of two
constexpr int kMinExponent = -10;
constexpr int kMaxExponent = 30;
constexpr std::size_t kBuckets =
    1 + static_cast<std::size_t>(kMaxExponent - kMinExponent) * kSubBuckets;

/// Bucket of `v` > 0: v = m * 2^e with m in [0.5, 1); (e, m) -> sub-bucket of the octave.
std::size_t bucket_of(double v) {
    int e = 0;
    const double m = std::frexp(v, &e);
    if (e <= kMinExponent) {
        return 0;
    }
    if (e > kMaxExponent) {
        return kBuckets - 1;
    }
    const auto sub = std::min(kSubBuckets - 1, static_cast<int>((2.0 * m - 1.0) * kSubBuckets));
    return 1 + static_cast<std::size_t>(e - kMinExponent - 1) * kSubBuckets +
           static_cast<std::size_t>(sub);
}

/// A representative value of bucket `b`: the middle of its range.
double value_of(std::size_t b) {
    if (b == 0) {
        return 0.0;
    }
    const auto octave = static_cast<int>((b - 1) / kSubBuckets);
    const auto sub = static_cast<int>((b - 1) % kSubBuckets);
    const double lo = 0.5 + 0.5 * sub / kSubBuckets;
    const double hi = 0.5 + 0.5 * (sub + 1) / kSubBuckets;
    return std::ldexp(0.5 * (lo + hi), octave + kMinExponent + 1);
}

} // namespace

void SampleHistogram::add(double value) {
    if (!std::isfinite(value) || value < 0.0) {
        return;
    }
    const std::size_t b = value > 0.0 ? bucket_of(value) : 0;
    if (b >= buckets_.size()) {
        buckets_.resize(b + 1, 0);
    }
    ++buckets_[b];
    ++count_;
    sum_ += value;
    max_ = std::max(max_, value);
}

void SampleHistogram::merge(const SampleHistogram& other) {
    if (other.buckets_.size() > buckets_.size()) {
        buckets_.resize(other.buckets_.size(), 0);
    }
    for (std::size_t b = 0; b < other.buckets_.size(); ++b) {
        buckets_[b] += other.buckets_[b];
    }
    count_ += other.count_;
    sum_ += other.sum_;
    max_ = std::max(max_, other.max_);
}

common::Summary SampleHistogram::summary() const {
    common::Summary s;
    s.count = static_cast<std::size_t>(count_);
    if (count_ == 0) {
        return s;
    }
    s.mean = sum_ / static_cast<double>(count_);
    s.max = max_;
    // Nearest rank, as common::percentile_sorted.
    const auto at_rank = [&](double q) {
        const double rank = std::max(1.0, std::ceil(q * static_cast<double>(count_)));
        std::uint64_t seen = 0;
        for (std::size_t b = 0; b < buckets_.size(); ++b) {
            seen += buckets_[b];
            if (static_cast<double>(seen) >= rank) {
                // The last bucket is open-ended: report the exact maximum there.
                return b == kBuckets - 1 ? max_ : std::min(value_of(b), max_);
            }
        }
        return max_;
    };
    s.p50 = at_rank(0.50);
    s.p95 = at_rank(0.95);
    s.p99 = at_rank(0.99);
    return s;
}

} // namespace dsoc::simclient
