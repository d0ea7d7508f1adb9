#include "dsoc/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace dsoc::eval {

Percentiles summarize(std::vector<float> values) {
    Percentiles p;
    if (values.empty()) {
        return p;
    }
    p.mean =
        std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
    const auto k =
        static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(values.size())) - 1.0);
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    p.p99 = values[k];
    p.max = *std::max_element(values.begin(), values.end());
    return p;
}

} // namespace dsoc::eval
