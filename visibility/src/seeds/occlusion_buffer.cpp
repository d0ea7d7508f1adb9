// Conservative cube-map z-pyramid. The key facts (docs/visibility.md has the proofs):
//  * Coverage: from an eye outside a convex solid, the set of ray directions that
//    hit it is a convex cone. A texel's directions are the convex hull of its four
//    corner rays, so if all four corner rays hit, every ray of the texel hits.
//  * Depth: along the ray eye + t*(F + u*R + v*U) (F the face axis, so t is view z),
//    the entry depth is max over front-facing planes of num_i / den_i(u,v), where
//    num_i = d_i - n_i.eye < 0 and den_i is linear in (u,v). With w_i = den_i / num_i
//    (also linear), entry z = 1 / min_front w_i and exit z = 1 / max_back w_i. Over a
//    fully covered texel every front plane has den_i < 0, so each plane's z is
//    monotone along any line and extremal at the corners: the max of the four corner
//    entry depths bounds the farthest entry depth over the texel.
//  * Margins: hits need min_front w > max_back w * (1 + 1e-4); written depths are
//    scaled up by 1 + 1e-4 and tested depths down by 1 - 1e-5, all toward `visible`.

#include "dsoc/visibility/seeds/occlusion_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dsoc::visibility {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kHitMargin = 1.0e-4f;
constexpr float kDepthUp = 1.0f + 1.0e-4f;
constexpr float kDepthDown = 1.0f - 1.0e-5f;
constexpr float kRectMargin = 1.0e-5f;
/// Planes passing within this distance of the eye are pushed inwards so the eye is
/// strictly outside them (shrinking the occluder is always conservative).
constexpr float kEyePlaneMargin = 1.0e-3f;
constexpr float kInvSqrt3 = 0.57735026f;

/// d - n.p in double: map coordinates reach thousands of units while the eye may be
/// a unit from the plane, and a float difference would lose the margins below.
float plane_offset(const Plane& plane, glm::vec3 p) {
    return static_cast<float>(static_cast<double>(plane.distance) -
                              glm::dot(glm::dvec3(plane.normal), glm::dvec3(p)));
}

/// B - R = [B.min - R.max, B.max - R.min], subtracted in double for the same reason.
Aabb difference_box(const Aabb& b, const Aabb& r) {
    return {glm::vec3(glm::dvec3(b.min) - glm::dvec3(r.max)),
            glm::vec3(glm::dvec3(b.max) - glm::dvec3(r.min))};
}

bool is_finite(const Aabb& b) {
    return std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) &&
           std::isfinite(b.max.x) && std::isfinite(b.max.y) && std::isfinite(b.max.z);
}

} // namespace

std::vector<std::string> validate(const OcclusionBufferConfig& c) {
    std::vector<std::string> problems;
    CubeZPyramid::check_settings(c.face_resolution, c.max_occluders, c.max_occluder_distance,
                                 problems);
    if (!(c.near_distance > 0.0f) || !std::isfinite(c.near_distance)) {
        problems.push_back("near_distance must be finite and > 0");
    }
    return problems;
}

OcclusionBuffer::OcclusionBuffer(const OcclusionBufferConfig& config) : config_(config) {
    if (!validate(config_).empty()) {
        // Invalid settings fall back to defaults rather than corrupting memory; a
        // server validates at start-up and refuses to run with them.
        config_ = OcclusionBufferConfig{};
    }
    pyramid_ = CubeZPyramid(config_.face_resolution);
    const int resolution = pyramid_.resolution();
    corner_u_.resize(static_cast<std::size_t>(resolution) + 1);
    for (int k = 0; k <= resolution; ++k) {
        corner_u_[static_cast<std::size_t>(k)] =
            -1.0f + 2.0f * static_cast<float>(k) / static_cast<float>(resolution);
    }
    const std::size_t row = static_cast<std::size_t>(resolution) + 1;
    row_prev_.resize(row);
    row_cur_.resize(row);
    w_front_.resize(row);
    w_back_.resize(row);
    coef_.resize(8 * 6 * kMaxOccluderPlanes);
    num_.resize(8 * kMaxOccluderPlanes);
    heap_.reserve(256);
}

void OcclusionBuffer::begin(glm::vec3 eye) {
    begin_region(Aabb{eye, eye});
}

void OcclusionBuffer::begin_region(const Aabb& region) {
    region_ = region;
    eye_ = region.center();
    region_mode_ = region.min != region.max;
    eye_count_ = region_mode_ ? 8 : 1;
    for (int j = 0; j < eye_count_; ++j) {
        eyes_[j] = region_mode_ ? glm::vec3((j & 1) ? region.max.x : region.min.x,
                                            (j & 2) ? region.max.y : region.min.y,
                                            (j & 4) ? region.max.z : region.min.z)
                                : eye_;
    }
    stats_ = {};
    any_written_ = false;
    pyramid_.clear_level0();
}

bool OcclusionBuffer::face_rect(int face, const Aabb& rel, float min_z, Rect& rect) const {
    const CubeFace& fa = kCubeFaces[face];
    float z_lo = fa.sign > 0.0f ? rel.min[fa.axis] : -rel.max[fa.axis];
    const float z_hi = fa.sign > 0.0f ? rel.max[fa.axis] : -rel.min[fa.axis];
    const float xl = rel.min[fa.right], xh = rel.max[fa.right];
    const float yl = rel.min[fa.up], yh = rel.max[fa.up];
    // Points in the face's (closed) frustum have z >= |x| and z >= |y|, so the box
    // part inside it is no nearer than the box's smallest |x| and |y|.
    const float min_abs_x = xl > 0.0f ? xl : (xh < 0.0f ? -xh : 0.0f);
    const float min_abs_y = yl > 0.0f ? yl : (yh < 0.0f ? -yh : 0.0f);
    z_lo = std::max(std::max(z_lo, min_z), std::max(min_abs_x, min_abs_y));
    if (!(z_hi >= z_lo)) {
        return false;
    }
    // u = x / z over the box part with z in [z_lo, z_hi]: extremal at the corners.
    const float inv_lo = 1.0f / z_lo;
    const float inv_hi = 1.0f / z_hi;
    const float u0 = std::min(xl * inv_lo, xl * inv_hi) - kRectMargin;
    const float u1 = std::max(xh * inv_lo, xh * inv_hi) + kRectMargin;
    const float v0 = std::min(yl * inv_lo, yl * inv_hi) - kRectMargin;
    const float v1 = std::max(yh * inv_lo, yh * inv_hi) + kRectMargin;
    if (u1 < -1.0f || u0 > 1.0f || v1 < -1.0f || v0 > 1.0f) {
        return false;
    }
    const float half = 0.5f * static_cast<float>(pyramid_.resolution());
    const int last = pyramid_.resolution() - 1;
    auto pixel = [&](float u) {
        const float p = std::clamp((u + 1.0f) * half, 0.0f, static_cast<float>(last));
        return static_cast<int>(p);
    };
    rect.x0 = pixel(u0);
    rect.x1 = pixel(u1);
    rect.y0 = pixel(v0);
    rect.y1 = pixel(v1);
    rect.z_near = z_lo;
    return true;
}

bool OcclusionBuffer::add_occluder(std::span<const Plane> planes, const Aabb& bounds) {
    ++stats_.occluders_visited;
    const std::size_t count = planes.size();
    if (count < 4 || count > kMaxOccluderPlanes || bounds.is_empty() || !is_finite(bounds)) {
        return false;
    }
    // num[j][i] = d_i - n_i.eye_j: negative when eye j is outside plane i.
    float* num = num_.data();
    if (!region_mode_) {
        bool eye_inside = true;
        for (std::size_t i = 0; i < count; ++i) {
            num[i] = plane_offset(planes[i], eye_);
            eye_inside = eye_inside && num[i] >= -kEyePlaneMargin;
            if (!std::isfinite(num[i])) {
                return false;
            }
        }
        if (eye_inside) {
            return false;
        }
        // Planes through (or almost through) the eye: push them inwards. This is one
        // fixed, smaller solid, so every argument above still applies to it.
        for (std::size_t i = 0; i < count; ++i) {
            if (num[i] > -kEyePlaneMargin && num[i] < kEyePlaneMargin) {
                num[i] = -kEyePlaneMargin;
            }
        }
    } else {
        // From a region: the occluder must lie strictly outside the whole region,
        // proven by one of its planes having every region corner outside it
        // (otherwise skip it; skipping is always conservative).
        bool separated = false;
        for (std::size_t i = 0; i < count; ++i) {
            float nearest = std::numeric_limits<float>::max();
            for (int j = 0; j < eye_count_; ++j) {
                const float v = plane_offset(planes[i], eyes_[j]);
                if (!std::isfinite(v)) {
                    return false;
                }
                num[static_cast<std::size_t>(j) * kMaxOccluderPlanes + i] = v;
                nearest = std::min(nearest, -v);
            }
            separated = separated || nearest > kEyePlaneMargin;
        }
        if (!separated) {
            return false;
        }
        // A plane passing (almost) through a corner eye would divide by ~0. Shrink
        // such planes for all eyes alike (one smaller solid); give up after a few
        // tries, which is conservative.
        for (std::size_t i = 0; i < count; ++i) {
            for (int attempt = 0;; ++attempt) {
                bool near_zero = false;
                for (int j = 0; j < eye_count_; ++j) {
                    const float v = num[static_cast<std::size_t>(j) * kMaxOccluderPlanes + i];
                    near_zero = near_zero || (v > -kEyePlaneMargin && v < kEyePlaneMargin);
                }
                if (!near_zero) {
                    break;
                }
                if (attempt == 4) {
                    return false;
                }
                for (int j = 0; j < eye_count_; ++j) {
                    num[static_cast<std::size_t>(j) * kMaxOccluderPlanes + i] -=
                        2.0f * kEyePlaneMargin;
                }
            }
        }
    }
    // Directions from any eye of the region to the occluder: the box O - R.
    const Aabb rel = difference_box(bounds, region_);
    const float dist = std::sqrt(distance_squared(rel, glm::vec3(0.0f)));
    const float min_z = std::max(dist * kInvSqrt3 * kDepthDown, 1.0e-4f);
    const std::int64_t before = stats_.texels_written;
    for (int face = 0; face < 6; ++face) {
        Rect rect;
        if (face_rect(face, rel, min_z, rect) &&
            !pyramid_.level0_hides(face, rect, rect.z_near, false)) {
            rasterize_face(face, rect, planes, num, count);
        }
    }
    const bool wrote = stats_.texels_written != before;
    stats_.occluders_written += wrote ? 1 : 0;
    any_written_ = any_written_ || wrote;
    return wrote;
}

void OcclusionBuffer::rasterize_face(int face, const Rect& rect, std::span<const Plane> planes,
                                     const float* num, std::size_t plane_count) {
    const CubeFace& fa = kCubeFaces[face];
    // Per eye j: w_ij(u, v) = (n.F + n.R u + n.U v) / num_ij, as (a, b, c) triples,
    // front planes (num < 0) first, then back planes.
    float* coef = coef_.data();
    std::size_t front_count[8];
    std::size_t back_count[8];
    for (int j = 0; j < eye_count_; ++j) {
        const float* nj = num + static_cast<std::size_t>(j) * kMaxOccluderPlanes;
        float* front = coef + static_cast<std::size_t>(j) * 6 * kMaxOccluderPlanes;
        float* back = front + 3 * kMaxOccluderPlanes;
        std::size_t fc = 0;
        std::size_t bc = 0;
        for (std::size_t i = 0; i < plane_count; ++i) {
            const glm::vec3 n = planes[i].normal;
            const float inv = 1.0f / nj[i];
            float* dst = nj[i] < 0.0f ? front + 3 * fc++ : back + 3 * bc++;
            dst[0] = n[fa.axis] * fa.sign * inv;
            dst[1] = n[fa.right] * inv;
            dst[2] = n[fa.up] * inv;
        }
        front_count[j] = fc;
        back_count[j] = bc;
    }
    const int cols = rect.x1 - rect.x0 + 2; // corners per row
    const float* u = corner_u_.data() + rect.x0;
    float* wf = w_front_.data();
    float* wb = w_back_.data();
    float* prev = row_prev_.data();
    float* cur = row_cur_.data();
    float* level0 = pyramid_.level_data(face, 0);
    std::int64_t written = 0;
    for (int cy = rect.y0; cy <= rect.y1 + 1; ++cy) {
        const float v = corner_u_[static_cast<std::size_t>(cy)];
        // cur[k]: the corner ray's entry depth, max over eyes; +inf when any misses.
        for (int k = 0; k < cols; ++k) {
            cur[k] = 0.0f;
        }
        for (int j = 0; j < eye_count_; ++j) {
            const float* front = coef + static_cast<std::size_t>(j) * 6 * kMaxOccluderPlanes;
            const float* back = front + 3 * kMaxOccluderPlanes;
            for (int k = 0; k < cols; ++k) {
                wf[k] = kInf;
                wb[k] = 0.0f;
            }
            for (std::size_t p = 0; p < front_count[j]; ++p) {
                const float base = front[3 * p] + front[3 * p + 2] * v;
                const float slope = front[3 * p + 1];
                for (int k = 0; k < cols; ++k) {
                    wf[k] = std::min(wf[k], base + slope * u[k]);
                }
            }
            for (std::size_t p = 0; p < back_count[j]; ++p) {
                const float base = back[3 * p] + back[3 * p + 2] * v;
                const float slope = back[3 * p + 1];
                for (int k = 0; k < cols; ++k) {
                    wb[k] = std::max(wb[k], base + slope * u[k]);
                }
            }
            for (int k = 0; k < cols; ++k) {
                // wb >= 0, so a hit also means wf > 0 (every front plane faces the
                // ray). Branch-free so it vectorizes; the division is masked on a miss.
                const bool hit = wf[k] > wb[k] * (1.0f + kHitMargin);
                const float depth = kDepthUp / wf[k];
                cur[k] = std::max(cur[k], hit ? depth : kInf);
            }
            if (j + 1 < eye_count_) {
                // Region mode: once every corner of the row misses from some eye,
                // the other eyes cannot change that.
                bool any_hit = false;
                for (int k = 0; k < cols; ++k) {
                    any_hit = any_hit || cur[k] < kInf;
                }
                if (!any_hit) {
                    break;
                }
            }
        }
        if (cy > rect.y0) {
            float* row =
                level0 + static_cast<std::size_t>(cy - 1) * pyramid_.resolution() + rect.x0;
            for (int k = 0; k + 1 < cols; ++k) {
                const float d =
                    std::max(std::max(prev[k], prev[k + 1]), std::max(cur[k], cur[k + 1]));
                written += d < row[k] ? 1 : 0;
                row[k] = std::min(row[k], d);
            }
        }
        std::swap(prev, cur);
    }
    stats_.texels_written += written;
}

void OcclusionBuffer::finish() {
    pyramid_.build_levels();
}

void OcclusionBuffer::build(glm::vec3 eye, const OccluderWorld& world, const BspTree& bsp) {
    build_region(Aabb{eye, eye}, world, bsp);
}

void OcclusionBuffer::build_region(const Aabb& region, const OccluderWorld& world,
                                   const BspTree& bsp) {
    begin_region(region);
    const glm::vec3 eye = region.center();
    const float max_d = config_.max_occluder_distance;
    const float max_sq = max_d * max_d;
    int budget = config_.max_occluders;
    if (budget > 0) {
        bsp.traverse_nearest_first(
            eye, heap_,
            [&](const BspNode& node) { return distance_squared(node.bounds, eye) <= max_sq; },
            [&](OccluderId id) {
                (void)add_occluder(world.solid_planes(id), world.occluder(id).bounds());
                return --budget > 0;
            });
    }
    finish();
}

Visibility OcclusionBuffer::test_box(const Aabb& box) const {
    if (!any_written_ || box.is_empty() || !is_finite(box)) {
        return Visibility::visible;
    }
    // Every vector from an eye of the region to a point of the box lies in B - R;
    // for a point eye this is just the box relative to the eye.
    const Aabb rel = difference_box(box, region_);
    const float d2 = distance_squared(rel, glm::vec3(0.0f));
    if (!(d2 > config_.near_distance * config_.near_distance)) {
        return Visibility::visible;
    }
    // Points of the box inside a face's frustum have view z >= |p - eye| / sqrt(3).
    const float min_z = std::sqrt(d2) * kInvSqrt3 * kDepthDown;
    int faces_touched = 0;
    for (int face = 0; face < 6; ++face) {
        Rect rect;
        if (!face_rect(face, rel, min_z, rect)) {
            continue;
        }
        ++faces_touched;
        if (!pyramid_.rect_occluded(face, rect, rect.z_near * kDepthDown)) {
            return Visibility::visible;
        }
    }
    return faces_touched > 0 ? Visibility::occluded : Visibility::visible;
}

} // namespace dsoc::visibility
