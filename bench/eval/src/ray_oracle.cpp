#include "dsoc/eval/ray_oracle.hpp"

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace dsoc::eval {

namespace {

RTCDevice as_device(void* p) {
    return static_cast<RTCDevice>(p);
}
RTCScene as_scene(void* p) {
    return static_cast<RTCScene>(p);
}

constexpr int kPacket = 16;

/// The ray parameter (0 at the eye, 1 at the point) kEndTrim from the start; 0.5 for a
/// segment shorter than two trims, which is then never blocked (all of it lies within
/// a trim of an end).
float end_trim(glm::vec3 d) {
    const float length = glm::length(d);
    return length > 2.0f * RayOracle::kEndTrim ? RayOracle::kEndTrim / length : 0.5f;
}

} // namespace

RayOracle::RayOracle(std::span<const visibility::ConvexPolyhedron> occluders,
                     std::span<const glm::vec3> triangles) {
    RTCDevice device = rtcNewDevice("threads=1");
    if (device == nullptr) {
        throw std::runtime_error("embree: rtcNewDevice failed");
    }
    device_ = device;
    RTCScene scene = rtcNewScene(device);
    scene_ = scene;
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);

    std::vector<float> vertices;
    std::vector<unsigned> indices;
    for (const auto& poly : occluders) {
        if (poly.is_empty()) {
            continue;
        }
        const auto base = static_cast<unsigned>(vertices.size() / 3);
        for (const glm::vec3& v : poly.vertices()) {
            vertices.insert(vertices.end(), {v.x, v.y, v.z});
        }
        for (const auto& face : poly.faces()) {
            const auto& vi = face.vertex_indices;
            for (std::size_t k = 2; k < vi.size(); ++k) {
                indices.insert(indices.end(), {base + vi[0], base + vi[k - 1], base + vi[k]});
            }
        }
    }
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
        const auto base = static_cast<unsigned>(vertices.size() / 3);
        for (std::size_t k = 0; k < 3; ++k) {
            const glm::vec3 v = triangles[t + k];
            vertices.insert(vertices.end(), {v.x, v.y, v.z});
        }
        indices.insert(indices.end(), {base, base + 1, base + 2});
    }
    triangles_ = indices.size() / 3;
    if (triangles_ > 0) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
            vertices.size() / 3 + 1)); // +1: Embree may read 16 bytes at the last vertex
        std::copy(vertices.begin(), vertices.end(), vb);
        auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles_));
        std::copy(indices.begin(), indices.end(), ib);
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        throw std::runtime_error("embree: building the occluder scene failed");
    }
}

RayOracle::~RayOracle() {
    rtcReleaseScene(as_scene(scene_));
    rtcReleaseDevice(as_device(device_));
}

bool RayOracle::segment_blocked(glm::vec3 from, glm::vec3 to) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    const glm::vec3 d = to - from;
    RTCRay ray{};
    ray.org_x = from.x;
    ray.org_y = from.y;
    ray.org_z = from.z;
    ray.dir_x = d.x;
    ray.dir_y = d.y;
    ray.dir_z = d.z;
    const float trim = end_trim(d);
    ray.tnear = trim;
    ray.tfar = 1.0f - trim;
    ray.mask = 0xffffffffu;
    rtcOccluded1(as_scene(scene_), &context, &ray);
    return ray.tfar < 0.0f; // Embree sets tfar to -inf on a hit
}

bool RayOracle::any_visible(glm::vec3 eye, std::span<const glm::vec3> points) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT; // one origin, nearby directions
    RTCRay16 rays;
    alignas(64) int valid[kPacket]; // Embree requires the mask 64-byte aligned
    for (std::size_t first = 0; first < points.size(); first += kPacket) {
        const std::size_t n = std::min<std::size_t>(kPacket, points.size() - first);
        for (int k = 0; k < kPacket; ++k) {
            const bool on = static_cast<std::size_t>(k) < n;
            valid[k] = on ? -1 : 0;
            const glm::vec3 p = on ? points[first + static_cast<std::size_t>(k)] : eye;
            rays.org_x[k] = eye.x;
            rays.org_y[k] = eye.y;
            rays.org_z[k] = eye.z;
            rays.dir_x[k] = p.x - eye.x;
            rays.dir_y[k] = p.y - eye.y;
            rays.dir_z[k] = p.z - eye.z;
            const float trim = end_trim(p - eye);
            rays.tnear[k] = trim;
            rays.tfar[k] = 1.0f - trim;
            rays.time[k] = 0.0f;
            rays.mask[k] = 0xffffffffu;
            rays.id[k] = static_cast<unsigned>(k);
            rays.flags[k] = 0;
        }
        rtcOccluded16(valid, as_scene(scene_), &context, &rays);
        for (std::size_t k = 0; k < n; ++k) {
            if (rays.tfar[k] >= 0.0f) {
                return true;
            }
        }
    }
    return false;
}

void RayOracle::box_samples(const visibility::Aabb& box, int grid, std::vector<glm::vec3>& out) {
    grid = std::max(grid, 2);
    out.push_back(box.center());
    for (int c = 0; c < 8; ++c) {
        out.emplace_back((c & 1) ? box.max.x : box.min.x, (c & 2) ? box.max.y : box.min.y,
                         (c & 4) ? box.max.z : box.min.z);
    }
    // Every lattice point of the box surface that is not a corner, once.
    const glm::vec3 step = (box.max - box.min) / static_cast<float>(grid - 1);
    for (int i = 0; i < grid; ++i) {
        for (int j = 0; j < grid; ++j) {
            for (int k = 0; k < grid; ++k) {
                const int on_x = (i == 0 || i == grid - 1) ? 1 : 0;
                const int on_y = (j == 0 || j == grid - 1) ? 1 : 0;
                const int on_z = (k == 0 || k == grid - 1) ? 1 : 0;
                const int boundary = on_x + on_y + on_z;
                if (boundary == 0 || boundary == 3) {
                    continue; // interior point, or a corner (already in)
                }
                const glm::vec3 p(
                    i == grid - 1 ? box.max.x : box.min.x + step.x * static_cast<float>(i),
                    j == grid - 1 ? box.max.y : box.min.y + step.y * static_cast<float>(j),
                    k == grid - 1 ? box.max.z : box.min.z + step.z * static_cast<float>(k));
                out.push_back(p);
            }
        }
    }
}

void RayOracle::front_samples(glm::vec3 eye, const visibility::Aabb& box, int grid,
                              std::vector<glm::vec3>& out) {
    grid = std::max(grid, 2);
    out.push_back(box.center());
    // side[a]: -1 when the eye is below the box on axis a (the min face faces it),
    // +1 above (the max face), 0 inside the slab (neither).
    int side[3];
    for (int a = 0; a < 3; ++a) {
        side[a] = eye[a] < box.min[a] ? -1 : (eye[a] > box.max[a] ? 1 : 0);
    }
    const float inv = 1.0f / static_cast<float>(grid - 1);
    for (int a = 0; a < 3; ++a) {
        if (side[a] == 0) {
            continue;
        }
        const int u = (a + 1) % 3;
        const int v = (a + 2) % 3;
        for (int i = 0; i < grid; ++i) {
            for (int j = 0; j < grid; ++j) {
                // A point on an edge shared with another front face of a lower axis
                // was already added by that face.
                const int ends[2] = {i == 0 ? -1 : (i == grid - 1 ? 1 : 0),
                                     j == 0 ? -1 : (j == grid - 1 ? 1 : 0)};
                const int axes[2] = {u, v};
                bool duplicate = false;
                for (int k = 0; k < 2; ++k) {
                    duplicate =
                        duplicate || (ends[k] != 0 && ends[k] == side[axes[k]] && axes[k] < a);
                }
                if (duplicate) {
                    continue;
                }
                glm::vec3 p;
                p[a] = side[a] < 0 ? box.min[a] : box.max[a];
                p[u] = i == grid - 1
                           ? box.max[u]
                           : box.min[u] + (box.max[u] - box.min[u]) * (static_cast<float>(i) * inv);
                p[v] = j == grid - 1
                           ? box.max[v]
                           : box.min[v] + (box.max[v] - box.min[v]) * (static_cast<float>(j) * inv);
                out.push_back(p);
            }
        }
    }
}

bool RayOracle::box_visible(glm::vec3 eye, const visibility::Aabb& box, int grid) const {
    if (box.contains(eye)) {
        return true;
    }
    thread_local std::vector<glm::vec3> samples;
    samples.clear();
    front_samples(eye, box, grid, samples);
    return any_visible(eye, samples);
}

} // namespace dsoc::eval
