#include "dsoc/maps/curved_surface.hpp"

#include <algorithm>
#include <cstddef>

namespace dsoc::maps {

namespace {

/// The quadratic Bezier curve through control points a, b, c at parameter t in [0, 1].
glm::vec3 bezier(glm::vec3 a, glm::vec3 b, glm::vec3 c, float t) {
    const float u = 1.0f - t;
    return (u * u) * a + (2.0f * u * t) * b + (t * t) * c;
}

} // namespace

void tessellate(const CurvedSurface& surface, int steps, std::vector<glm::vec3>& triangles) {
    steps = std::max(steps, 1);
    const auto at = [&](int row, int column) {
        return surface.points[static_cast<std::size_t>(row * surface.width + column)];
    };
    const auto n = static_cast<std::size_t>(steps) + 1;
    std::vector<glm::vec3> grid(n * n);
    for (int row = 0; row + 2 < surface.height; row += 2) {
        for (int column = 0; column + 2 < surface.width; column += 2) {
            for (int i = 0; i <= steps; ++i) {
                const float s = static_cast<float>(i) / static_cast<float>(steps);
                // The three control rows evaluated along the columns at s, then across.
                const glm::vec3 r0 =
                    bezier(at(row, column), at(row, column + 1), at(row, column + 2), s);
                const glm::vec3 r1 = bezier(at(row + 1, column), at(row + 1, column + 1),
                                            at(row + 1, column + 2), s);
                const glm::vec3 r2 = bezier(at(row + 2, column), at(row + 2, column + 1),
                                            at(row + 2, column + 2), s);
                for (int j = 0; j <= steps; ++j) {
                    const float t = static_cast<float>(j) / static_cast<float>(steps);
                    grid[static_cast<std::size_t>(i) * n + static_cast<std::size_t>(j)] =
                        bezier(r0, r1, r2, t);
                }
            }
            for (std::size_t i = 0; i + 1 < n; ++i) {
                for (std::size_t j = 0; j + 1 < n; ++j) {
                    const glm::vec3 a = grid[i * n + j];
                    const glm::vec3 b = grid[(i + 1) * n + j];
                    const glm::vec3 c = grid[(i + 1) * n + j + 1];
                    const glm::vec3 d = grid[i * n + j + 1];
                    triangles.insert(triangles.end(), {a, b, c, a, c, d});
                }
            }
        }
    }
}

} // namespace dsoc::maps
