#include "dsoc/visibility/geometry.hpp"

#include <cmath>

namespace dsoc::visibility {

Frustum Frustum::perspective(glm::vec3 eye, glm::vec3 forward, glm::vec3 up, float fov_y,
                             float aspect, float near_distance, float far_distance) {
    const glm::vec3 f = glm::normalize(forward);
    const glm::vec3 r = glm::normalize(glm::cross(f, up));
    const glm::vec3 u = glm::cross(r, f);
    const float ty = std::tan(fov_y * 0.5f);
    const float tx = ty * aspect;
    Frustum frustum;
    auto through_eye = [&](glm::vec3 n) {
        n = glm::normalize(n);
        return Plane{n, glm::dot(n, eye)};
    };
    frustum.planes[0] = Plane{-f, -glm::dot(f, eye + f * near_distance)};
    frustum.planes[1] = Plane{f, glm::dot(f, eye + f * far_distance)};
    // Side planes contain the eye; outward normals.
    frustum.planes[2] = through_eye(r - f * tx);  // right
    frustum.planes[3] = through_eye(-r - f * tx); // left
    frustum.planes[4] = through_eye(u - f * ty);  // top
    frustum.planes[5] = through_eye(-u - f * ty); // bottom
    frustum.plane_count = 6;
    return frustum;
}

} // namespace dsoc::visibility
