// From-region cube-map z-pyramid with extended projections. The key facts
// (docs/region-visibility.md has the full argument):
//  * Partition: for an eye p in the region R (strictly inside the cube of half-size D
//    around R's centre c) and any point q, the ray p -> q leaves the cube through a
//    face at an exit point y. Pairs (p, q) are assigned to the face they leave by.
//  * Coverage: y is "near-blocked" by a convex occluder O when for every p in R the
//    open segment (p, y) meets O's interior, and "far-blocked" when for every p the
//    ray beyond y does. For fixed y, either set of eyes p is convex (the shadow of O
//    lit from y, resp. the reflected cone), so R's corners decide it; for fixed p the
//    set of such y on the plane is convex, hence their intersection over p is too,
//    and a texel is inside it when its four corners are. A texel is written when its
//    corners are all near-blocked or all far-blocked (the union of both kinds is not
//    convex, so they are never mixed).
//  * Depth: along p -> q the axis coordinate grows monotonically, so if q's axis
//    coordinate exceeds the depth where the ray enters O, the segment met O before
//    reaching q. Each plane's entry depth is linear-fractional in y for a fixed eye
//    and in the eye for a fixed y (the quadratic terms cancel), with a fixed-sign
//    denominator on a covered texel, so the max over region x texel is at region
//    corners x texel corners, or at an eye on the plane (depth <= h_a). O's extent
//    along the axis (before the plane, for near-blocked texels) caps it.
//  * Ray test without divisions: for region corner k and plane i, a = d_i - n_i.p_k
//    and b = n_i.(y - p_k) (linear in the face coordinates). With w = b / a, planes
//    with a < 0 (p_k outside) give the entry t = 1 / min w (a hit needs min w > 0) and
//    planes with a > 0 give the exit t = 1 / max w (no exit when max w <= 0), so w is
//    linear in (s, t) with per-occluder coefficients: rows are evaluated incrementally.
//  * Margins, all towards `visible`: planes are pushed inwards by kShrink, hits need
//    relative slack kHitMargin in t, written depths are raised and tested depths
//    lowered, rectangles are widened.

#include "dsoc/visibility/region_occlusion_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dsoc::visibility {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
/// Occluder planes are moved this far into the solid (world units).
constexpr double kShrink = 2.0e-2;
/// |a| below this is replaced by -kMinA: the corner is treated as just outside the
/// plane, which shrinks the occluder as seen from it.
constexpr double kMinA = 1.0e-3;
/// Relative slack on the ray parameter t for a hit.
constexpr float kHitMargin = 1.0e-4f;
/// Written depths are raised by this (relative and absolute).
constexpr float kDepthUpRel = 1.0e-5f;
constexpr float kDepthUpAbs = 1.0e-2f;
/// Tested depths are lowered by this (relative and absolute).
constexpr float kDepthDownRel = 1.0e-5f;
constexpr float kDepthDownAbs = 1.0e-2f;
/// Face-coordinate slack on every rectangle.
constexpr float kRectMargin = 1.0e-4f;
/// Lower bound on w when converting it to an entry depth (t = 1 / w).
constexpr float kTinyW = 1.0e-12f;
/// Occluders and boxes within this distance of the region are not used / visible.
constexpr float kRegionMargin = 1.0f;

/// The extent [lo, hi] of the box [rel_min, rel_max] (relative to the centre) along
/// the direction face `fa` looks in.
void oriented_extent(const CubeFace& fa, glm::vec3 rel_min, glm::vec3 rel_max, float& lo,
                     float& hi) {
    lo = fa.sign > 0.0f ? rel_min[fa.axis] : -rel_max[fa.axis];
    hi = fa.sign > 0.0f ? rel_max[fa.axis] : -rel_min[fa.axis];
}

/// Squared distance between two non-empty boxes (0 when they overlap).
float box_distance_squared(const Aabb& a, const Aabb& b) {
    const glm::vec3 gap = glm::max(glm::max(a.min - b.max, b.min - a.max), glm::vec3(0.0f));
    return glm::dot(gap, gap);
}

bool finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Interval of face coordinate (p_u + (D - p_a) m) / D over p_u in [-hu, hu],
/// p_a in [-ha, ha] and m in [m_lo, m_hi] (D > ha): bilinear, extremal at corners.
void exit_interval(float hu, float ha, float distance, float m_lo, float m_hi, float& lo,
                   float& hi) {
    const float near_scale = distance - ha; // smallest D - p_a
    const float far_scale = distance + ha;  // largest D - p_a
    lo = (-hu + (m_lo < 0.0f ? far_scale : near_scale) * m_lo) / distance;
    hi = (hu + (m_hi > 0.0f ? far_scale : near_scale) * m_hi) / distance;
}

/// Range of num / den over num in [n_lo, n_hi], den in [d_lo, d_hi] with d_lo > 0.
void ratio_range(float n_lo, float n_hi, float d_lo, float d_hi, float& lo, float& hi) {
    lo = n_lo / (n_lo >= 0.0f ? d_hi : d_lo);
    hi = n_hi / (n_hi >= 0.0f ? d_lo : d_hi);
}

} // namespace

std::vector<std::string> validate(const RegionOcclusionBufferConfig& c) {
    std::vector<std::string> problems;
    CubeZPyramid::check_settings(c.face_resolution, c.max_occluders, c.max_occluder_distance,
                                 problems);
    if (!(c.projection_distance > 0.0f) || !std::isfinite(c.projection_distance)) {
        problems.push_back("projection_distance must be finite and > 0");
    }
    return problems;
}

RegionOcclusionBuffer::RegionOcclusionBuffer(const RegionOcclusionBufferConfig& config)
    : config_(config) {
    if (!validate(config_).empty()) {
        // Invalid settings fall back to defaults rather than corrupting memory; a
        // server validates at start-up and refuses to run with them.
        config_ = RegionOcclusionBufferConfig{};
    }
    pyramid_ = CubeZPyramid(config_.face_resolution);
    const int resolution = pyramid_.resolution();
    const std::size_t corners = static_cast<std::size_t>(resolution) + 1;
    grid_s_.resize(corners);
    for (int k = 0; k <= resolution; ++k) {
        grid_s_[static_cast<std::size_t>(k)] =
            -1.0f + 2.0f * static_cast<float>(k) / static_cast<float>(resolution);
    }
    wf_.resize(corners);
    wb_.resize(corners);
    entry_prev_.resize(corners);
    entry_cur_.resize(corners);
    near_prev_.resize(corners);
    near_cur_.resize(corners);
    far_prev_.resize(corners);
    far_cur_.resize(corners);
    heap_.reserve(256);
}

void RegionOcclusionBuffer::begin(const Aabb& eye_region) {
    region_ = eye_region;
    stats_ = {};
    any_written_ = false;
    valid_region_ = !eye_region.is_empty() && finite(eye_region.min) && finite(eye_region.max);
    pyramid_.clear_level0();
    corner_count_ = 0;
    if (!valid_region_) {
        return;
    }
    center_ = eye_region.center();
    half_ = glm::max(eye_region.half_extents(), glm::vec3(0.0f));
    distance_ = std::max(config_.projection_distance, 1.25f * glm::length(half_) + 1.0f);
    stats_.projection_distance = distance_;
    // Corners relative to the centre; a zero extent gives one value on that axis.
    const int nx = half_.x > 0.0f ? 2 : 1;
    const int ny = half_.y > 0.0f ? 2 : 1;
    const int nz = half_.z > 0.0f ? 2 : 1;
    for (int ix = 0; ix < nx; ++ix) {
        for (int iy = 0; iy < ny; ++iy) {
            for (int iz = 0; iz < nz; ++iz) {
                corner_[corner_count_++] =
                    glm::vec3(ix == 0 ? -half_.x : half_.x, iy == 0 ? -half_.y : half_.y,
                              iz == 0 ? -half_.z : half_.z);
            }
        }
    }
}

bool RegionOcclusionBuffer::texel_range(float lo, float hi, int& first, int& last) const {
    lo -= kRectMargin;
    hi += kRectMargin;
    if (!(lo <= hi) || hi < -1.0f || lo > 1.0f) {
        return false;
    }
    const float half = 0.5f * static_cast<float>(pyramid_.resolution());
    const float top = static_cast<float>(pyramid_.resolution() - 1);
    first = static_cast<int>(std::clamp((lo + 1.0f) * half, 0.0f, top));
    last = static_cast<int>(std::clamp((hi + 1.0f) * half, 0.0f, top));
    return true;
}

bool RegionOcclusionBuffer::add_occluder(std::span<const Plane> planes, const Aabb& bounds) {
    ++stats_.occluders_visited;
    const std::size_t count = planes.size();
    if (!valid_region_ || count < 4 || count > kMaxOccluderPlanes || bounds.is_empty() ||
        !finite(bounds.min) || !finite(bounds.max)) {
        return false;
    }
    // Occluders touching the region (or within kRegionMargin) write nothing. The
    // test is conservative towards skipping: bounds overlap and no face plane of the
    // occluder separates it from the grown region.
    const Aabb grown = region_.expanded(kRegionMargin);
    if (bounds.overlaps(grown)) {
        bool separated = false;
        for (const Plane& p : planes) {
            if (p.signed_distance(grown.center()) > projected_radius(grown, p.normal)) {
                separated = true;
                break;
            }
        }
        if (!separated) {
            ++stats_.occluders_skipped_region;
            return false;
        }
    }
    // Plane offsets relative to the centre, in double, pushed into the solid.
    double offset[kMaxOccluderPlanes];
    const glm::dvec3 c(center_);
    for (std::size_t i = 0; i < count; ++i) {
        offset[i] = static_cast<double>(planes[i].distance) -
                    glm::dot(glm::dvec3(planes[i].normal), c) - kShrink;
        if (!std::isfinite(offset[i])) {
            return false;
        }
    }
    const glm::vec3 rel_min = bounds.min - center_;
    const glm::vec3 rel_max = bounds.max - center_;
    const float d = distance_;
    const float min_forward =
        min_forward_distance(std::sqrt(box_distance_squared(bounds, region_)));
    const std::int64_t before = stats_.texels_written;
    for (int face = 0; face < 6; ++face) {
        const CubeFace& fa = kCubeFaces[face];
        // Oriented extent of the occluder along the face direction.
        float oa0 = 0.0f;
        float oa1 = 0.0f;
        oriented_extent(fa, rel_min, rel_max, oa0, oa1);
        const float ha = half_[fa.axis];
        if (!(oa1 > ha)) {
            continue; // behind the most advanced corner: no ray from it reaches O here
        }
        // Rectangle: intersection over the corners of the projections of O's bounds.
        // Only O's part at least min_forward ahead of the corner can be hit by a ray
        // leaving through this face (see test_box), which bounds the projection.
        float s_lo = -1.0f, s_hi = 1.0f, t_lo = -1.0f, t_hi = 1.0f;
        bool none = false;
        for (int k = 0; k < corner_count_; ++k) {
            const float pa = fa.sign * corner_[k][fa.axis];
            const float den_lo = std::max(oa0 - pa, min_forward);
            const float den_hi = oa1 - pa;
            if (!(den_hi >= den_lo)) {
                none = true; // no part of O is in this corner's frustum
                break;
            }
            if (!(den_lo > 1.0e-3f)) {
                continue; // O reaches back to this corner: unbounded projection
            }
            const float scale = (d - pa) / d;
            const float pu = corner_[k][fa.right] / d;
            const float pv = corner_[k][fa.up] / d;
            float m_lo, m_hi;
            ratio_range(rel_min[fa.right] - corner_[k][fa.right],
                        rel_max[fa.right] - corner_[k][fa.right], den_lo, den_hi, m_lo, m_hi);
            s_lo = std::max(s_lo, pu + scale * m_lo);
            s_hi = std::min(s_hi, pu + scale * m_hi);
            ratio_range(rel_min[fa.up] - corner_[k][fa.up], rel_max[fa.up] - corner_[k][fa.up],
                        den_lo, den_hi, m_lo, m_hi);
            t_lo = std::max(t_lo, pv + scale * m_lo);
            t_hi = std::min(t_hi, pv + scale * m_hi);
        }
        Rect rect;
        if (none || !texel_range(s_lo, s_hi, rect.x0, rect.x1) ||
            !texel_range(t_lo, t_hi, rect.y0, rect.y1)) {
            continue;
        }
        // Near-blocked texels are blocked by O's part before the plane (axis < D).
        const float depth_far = oa1 * (1.0f + kDepthUpRel) + kDepthUpAbs;
        const float depth_near = std::min(oa1, d) * (1.0f + kDepthUpRel) + kDepthUpAbs;
        // Every depth this occluder writes is at least its nearest extent.
        if (pyramid_.level0_hides(face, rect, std::max(oa0, ha), true)) {
            continue;
        }
        rasterize_face(face, rect, planes, offset, depth_near, depth_far);
    }
    const bool wrote = stats_.texels_written != before;
    stats_.occluders_written += wrote ? 1 : 0;
    any_written_ = any_written_ || wrote;
    return wrote;
}

void RegionOcclusionBuffer::rasterize_face(int face, const Rect& rect,
                                           std::span<const Plane> planes,
                                           const double* plane_offset, float depth_near,
                                           float depth_far) {
    const CubeFace& fa = kCubeFaces[face];
    const double d = static_cast<double>(distance_);
    // w = b / a = c0 + ct * t + cs * s per (corner, plane), split into planes the
    // corner is outside of (front: entry) and inside of (back: exit).
    struct Coef {
        float c0, ct, cs;
    };
    Coef front[kMaxRegionCorners][kMaxOccluderPlanes];
    Coef back[kMaxRegionCorners][kMaxOccluderPlanes];
    int front_count[kMaxRegionCorners];
    int back_count[kMaxRegionCorners];
    const std::size_t count = planes.size();
    for (int k = 0; k < corner_count_; ++k) {
        const glm::dvec3 p(corner_[k]);
        front_count[k] = 0;
        back_count[k] = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const glm::dvec3 n(planes[i].normal);
            const double np = glm::dot(n, p);
            double a = plane_offset[i] - np;
            if (std::abs(a) < kMinA) {
                a = -kMinA;
            }
            const double inv = 1.0 / a;
            const Coef coef{static_cast<float>((d * fa.sign * n[fa.axis] - np) * inv),
                            static_cast<float>(d * n[fa.up] * inv),
                            static_cast<float>(d * n[fa.right] * inv)};
            if (a < 0.0) {
                front[k][front_count[k]++] = coef;
            } else {
                back[k][back_count[k]++] = coef;
            }
        }
        if (front_count[k] == 0) {
            return; // this corner is inside O (the region test should have caught it)
        }
    }
    const int cols = rect.x1 - rect.x0 + 2; // texel corners per row
    const float* s = grid_s_.data() + rect.x0;
    float* wf = wf_.data();
    float* wb = wb_.data();
    float* entry_prev = entry_prev_.data();
    float* entry_cur = entry_cur_.data();
    std::uint8_t* near_prev = near_prev_.data();
    std::uint8_t* near_cur = near_cur_.data();
    std::uint8_t* far_prev = far_prev_.data();
    std::uint8_t* far_cur = far_cur_.data();
    float* level0 = pyramid_.level_data(face, 0);
    std::int64_t written = 0;
    std::int64_t evaluated = 0;
    // Entry points of rays from eyes that lie on an occluder plane are the eyes
    // themselves: their depth is at most the region's half extent.
    const float floor_depth = half_[fa.axis];
    constexpr float kUp = 1.0f + kHitMargin;
    constexpr float kBelowOne = 1.0f - kHitMargin;
    for (int cy = rect.y0; cy <= rect.y1 + 1; ++cy) {
        const float t = grid_s_[static_cast<std::size_t>(cy)];
        for (int x = 0; x < cols; ++x) {
            near_cur[x] = 1;
            far_cur[x] = 1;
            entry_cur[x] = 0.0f;
        }
        // Columns [lo, hi) may still be blocked for every eye; the others are 0.
        int lo = 0;
        int hi = cols;
        for (int k = 0; k < corner_count_ && lo < hi; ++k) {
            const float pa = fa.sign * corner_[k][fa.axis];
            const float span = distance_ - pa;
            evaluated += hi - lo;
            for (int x = lo; x < hi; ++x) {
                wf[x] = kInf;
                wb[x] = 0.0f;
            }
            for (int i = 0; i < front_count[k]; ++i) {
                const Coef& cf = front[k][i];
                const float base = cf.c0 + cf.ct * t;
                for (int x = lo; x < hi; ++x) {
                    wf[x] = std::min(wf[x], base + cf.cs * s[x]);
                }
            }
            for (int i = 0; i < back_count[k]; ++i) {
                const Coef& cf = back[k][i];
                const float base = cf.c0 + cf.ct * t;
                for (int x = lo; x < hi; ++x) {
                    wb[x] = std::max(wb[x], base + cf.cs * s[x]);
                }
            }
            // Entry t = 1/wf, exit t = 1/wb (wb >= 0; 0 = no exit).
            // Near: entry < min(exit, 1). Far: max(entry, 1) < exit.
            for (int x = lo; x < hi; ++x) {
                const bool near_hit = wf[x] > std::max(wb[x], 1.0f) * kUp;
                const bool far_hit = wf[x] > wb[x] * kUp && wb[x] < kBelowOne;
                near_cur[x] = static_cast<std::uint8_t>(near_cur[x] & (near_hit ? 1 : 0));
                far_cur[x] = static_cast<std::uint8_t>(far_cur[x] & (far_hit ? 1 : 0));
                // Oriented axis coordinate of the entry point (meaningful on hits).
                const float entry = pa + span / std::max(wf[x], kTinyW);
                entry_cur[x] = std::max(entry_cur[x], entry);
            }
            // Shrink the live column range for the remaining corners.
            while (lo < hi && (near_cur[lo] | far_cur[lo]) == 0) {
                ++lo;
            }
            while (hi > lo && (near_cur[hi - 1] | far_cur[hi - 1]) == 0) {
                --hi;
            }
        }
        if (cy > rect.y0) {
            float* row =
                level0 + static_cast<std::size_t>(cy - 1) * pyramid_.resolution() + rect.x0;
            for (int x = 0; x + 1 < cols; ++x) {
                const bool near =
                    (near_prev[x] & near_prev[x + 1] & near_cur[x] & near_cur[x + 1]) != 0;
                const bool far = (far_prev[x] & far_prev[x + 1] & far_cur[x] & far_cur[x + 1]) != 0;
                // Entry depths are extremal at the region's and the texel's corners
                // (see the file comment); O's bounds cap them.
                const float entry = std::max(std::max(entry_prev[x], entry_prev[x + 1]),
                                             std::max(entry_cur[x], entry_cur[x + 1]));
                const float cap = near ? depth_near : depth_far;
                const float z =
                    (near || far)
                        ? std::min(cap, std::max(entry, floor_depth) * (1.0f + kDepthUpRel) +
                                            kDepthUpAbs)
                        : kInf;
                written += z < row[x] ? 1 : 0;
                row[x] = std::min(row[x], z);
            }
        }
        std::swap(entry_prev, entry_cur);
        std::swap(near_prev, near_cur);
        std::swap(far_prev, far_cur);
    }
    stats_.texels_written += written;
    stats_.corners_evaluated += evaluated;
}

void RegionOcclusionBuffer::finish() {
    pyramid_.build_levels();
}

void RegionOcclusionBuffer::build(const Aabb& eye_region, const OccluderWorld& world,
                                  const BspTree& bsp) {
    begin(eye_region);
    if (valid_region_ && config_.max_occluders > 0) {
        const float max_d = config_.max_occluder_distance;
        const float max_sq = max_d * max_d;
        int budget = config_.max_occluders;
        bsp.traverse_nearest_first(
            center_, heap_,
            [&](const BspNode& node) {
                return box_distance_squared(node.bounds, region_) <= max_sq;
            },
            [&](OccluderId id) {
                (void)add_occluder(world.solid_planes(id), world.occluder(id).bounds());
                return --budget > 0;
            });
    }
    finish();
}

float RegionOcclusionBuffer::min_forward_distance(float distance) const {
    // A ray from an eye p of R leaving by a face has |lateral| <= forward * (D + h) /
    // (D - h) on both lateral axes, so any point x on it has a forward offset
    // x_a - p_a >= |x - p| / sqrt(1 + 2 / k^2) with k = (D - h) / (D + h).
    const float h_max = std::max(std::max(half_.x, half_.y), half_.z);
    const float k = (distance_ - h_max) / (distance_ + h_max);
    return distance / std::sqrt(1.0f + 2.0f / (k * k)) * (1.0f - 1.0e-5f);
}

Visibility RegionOcclusionBuffer::test_box(const Aabb& box) const {
    if (!any_written_ || box.is_empty() || !finite(box.min) || !finite(box.max)) {
        return Visibility::visible;
    }
    const float dist_sq = box_distance_squared(box, region_);
    if (!(dist_sq > kRegionMargin * kRegionMargin)) {
        return Visibility::visible;
    }
    // A pair (p, q) leaving by a face has |lateral| <= forward * (D + h) / (D - h) on
    // both lateral axes, so its forward component is at least |q - p| / sqrt(1 + 2/k^2).
    const float d = distance_;
    const float min_forward = min_forward_distance(std::sqrt(dist_sq));
    const glm::vec3 rel_min = box.min - center_;
    const glm::vec3 rel_max = box.max - center_;
    int faces_touched = 0;
    for (int face = 0; face < 6; ++face) {
        const CubeFace& fa = kCubeFaces[face];
        float ba0 = 0.0f;
        float ba1 = 0.0f;
        oriented_extent(fa, rel_min, rel_max, ba0, ba1);
        const float ha = half_[fa.axis];
        // Forward component q_a - p_a of the pairs leaving by this face.
        const float fwd_lo = std::max(ba0 - ha, min_forward);
        const float fwd_hi = ba1 + ha;
        if (fwd_hi < fwd_lo) {
            continue; // no pair leaves by this face
        }
        float m_lo, m_hi, s_lo, s_hi, t_lo, t_hi;
        if (ba0 - ha >= min_forward) {
            // Every pair goes forward: for a fixed eye the exit coordinate is monotone
            // in the slope, the slope's range over the box is attained at its corners,
            // and for a fixed q the exit coordinate is linear-fractional in the eye
            // with a positive denominator, so R's corners bound it: exact bounds.
            s_lo = t_lo = kInf;
            s_hi = t_hi = -kInf;
            for (int c = 0; c < corner_count_; ++c) {
                const glm::vec3& p = corner_[c];
                const float pa = fa.sign * p[fa.axis];
                const float den_lo = ba0 - pa;
                const float den_hi = ba1 - pa;
                const float scale = (d - pa) / d;
                ratio_range(rel_min[fa.right] - p[fa.right], rel_max[fa.right] - p[fa.right],
                            den_lo, den_hi, m_lo, m_hi);
                s_lo = std::min(s_lo, p[fa.right] / d + scale * m_lo);
                s_hi = std::max(s_hi, p[fa.right] / d + scale * m_hi);
                ratio_range(rel_min[fa.up] - p[fa.up], rel_max[fa.up] - p[fa.up], den_lo, den_hi,
                            m_lo, m_hi);
                t_lo = std::min(t_lo, p[fa.up] / d + scale * m_lo);
                t_hi = std::max(t_hi, p[fa.up] / d + scale * m_hi);
            }
        } else {
            // Some pairs are nearly sideways: bound eye and slope independently.
            ratio_range(rel_min[fa.right] - half_[fa.right], rel_max[fa.right] + half_[fa.right],
                        fwd_lo, fwd_hi, m_lo, m_hi);
            exit_interval(half_[fa.right], ha, d, m_lo, m_hi, s_lo, s_hi);
            ratio_range(rel_min[fa.up] - half_[fa.up], rel_max[fa.up] + half_[fa.up], fwd_lo,
                        fwd_hi, m_lo, m_hi);
            exit_interval(half_[fa.up], ha, d, m_lo, m_hi, t_lo, t_hi);
        }
        Rect rect;
        if (!texel_range(s_lo, s_hi, rect.x0, rect.x1) ||
            !texel_range(t_lo, t_hi, rect.y0, rect.y1)) {
            continue; // every exit point misses this face
        }
        ++faces_touched;
        // Nearest oriented axis coordinate of any q of such a pair.
        const float z = std::max(ba0, min_forward - ha);
        const float z_test = z - std::abs(z) * kDepthDownRel - kDepthDownAbs;
        if (!pyramid_.rect_occluded(face, rect, z_test)) {
            return Visibility::visible;
        }
    }
    return faces_touched > 0 ? Visibility::occluded : Visibility::visible;
}

} // namespace dsoc::visibility
