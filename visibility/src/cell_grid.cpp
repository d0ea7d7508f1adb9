#include "dsoc/visibility/cell_grid.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::visibility {

namespace {
/// How far range_of() widens a box, as a fraction of a cell.
constexpr float kRangeSlack = 1.0f / 1024.0f;
} // namespace

CellGrid CellGrid::covering(const Aabb& bounds, float cell_size) {
    CellGrid g;
    g.cell_size = cell_size;
    g.origin = bounds.min;
    for (int a = 0; a < 3; ++a) {
        g.dims[a] =
            std::max(1, static_cast<int>(std::ceil((bounds.max[a] - bounds.min[a]) / cell_size)));
    }
    return g;
}

Aabb CellGrid::cell_box(glm::ivec3 c) const {
    const glm::vec3 lo = origin + glm::vec3(c) * cell_size;
    return {lo, lo + glm::vec3(cell_size)};
}

Aabb CellGrid::bounds() const {
    return {origin, origin + glm::vec3(dims) * cell_size};
}

bool CellGrid::range_of(const Aabb& box, glm::ivec3& lo, glm::ivec3& hi) const {
    if (box.is_empty() || cell_size <= 0.0f) {
        return false;
    }
    const Aabb all = bounds();
    if (!all.contains(box)) {
        return false;
    }
    for (int a = 0; a < 3; ++a) {
        const float from = (box.min[a] - origin[a]) / cell_size - kRangeSlack;
        const float to = (box.max[a] - origin[a]) / cell_size + kRangeSlack;
        if (!std::isfinite(from) || !std::isfinite(to)) {
            return false;
        }
        lo[a] = std::clamp(static_cast<int>(std::floor(from)), 0, dims[a] - 1);
        hi[a] = std::clamp(static_cast<int>(std::floor(to)), 0, dims[a] - 1);
    }
    return true;
}

} // namespace dsoc::visibility
