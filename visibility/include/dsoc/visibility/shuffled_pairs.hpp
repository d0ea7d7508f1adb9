#pragma once
// The unordered pairs {i, j} (i <= j, a pair of an item with itself included) of n
// items, in a scattered order, by index: the k-th pair for any k in [0, count()), with
// no list held. The bake hands pairs of top blocks to its workers in this order, so
// that cost is spread evenly over time (progress and ETA stay honest) with memory that
// does not grow as n² (a map of 100,000 top blocks has 5·10⁹ pairs).

#include <cmath>
#include <cstdint>
#include <utility>

namespace dsoc::visibility {

class ShuffledPairs {
public:
    /// `n` items. [Limit: n <= 2^31]
    explicit ShuffledPairs(std::uint64_t n) : n_(n), count_(n * (n + 1) / 2) {
        while ((std::uint64_t{1} << bits_) < count_) {
            ++bits_;
        }
    }

    [[nodiscard]] std::uint64_t count() const { return count_; }

    /// The k-th pair (k < count()): every pair exactly once as k runs over [0, count()).
    [[nodiscard]] std::pair<std::uint32_t, std::uint32_t> at(std::uint64_t k) const {
        return pair_of(scatter(k));
    }

private:
    /// A bijection of [0, count()): a bijection of the bits_-bit numbers (odd
    /// multipliers and xor-shifts are each one), applied again while the result is not
    /// below count() (cycle walking keeps it a bijection of the smaller range).
    [[nodiscard]] std::uint64_t scatter(std::uint64_t k) const {
        if (bits_ == 0) {
            return k;
        }
        const std::uint64_t mask =
            bits_ == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits_) - 1;
        const int half = (bits_ + 1) / 2;
        do {
            k = (k * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) & mask;
            k ^= k >> half;
            k = (k * 0xBF58476D1CE4E5B9ull) & mask;
            k ^= k >> half;
        } while (k >= count_);
        return k;
    }

    /// Row-major over i: row i holds the pairs {i, i}, {i, i + 1}, ..., {i, n - 1}; the
    /// rows before it hold i·n - i(i - 1)/2 pairs.
    [[nodiscard]] std::pair<std::uint32_t, std::uint32_t> pair_of(std::uint64_t k) const {
        const auto before = [this](std::uint64_t i) { return i * n_ - i * (i - 1) / 2; };
        // The largest i with before(i) <= k, from the quadratic's root, then corrected
        // for the float's rounding.
        const double b = 2.0 * static_cast<double>(n_) + 1.0;
        const double root = (b - std::sqrt(b * b - 8.0 * static_cast<double>(k))) / 2.0;
        auto i = static_cast<std::uint64_t>(std::max(0.0, std::floor(root)));
        while (i > 0 && before(i) > k) {
            --i;
        }
        while (i + 1 < n_ && before(i + 1) <= k) {
            ++i;
        }
        return {static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i + (k - before(i)))};
    }

    std::uint64_t n_;
    std::uint64_t count_;
    int bits_ = 0;
};

} // namespace dsoc::visibility
