// The single-occluder shaft tests: does one convex solid (planes, or an axis box) block
// every segment from a region to a box (the 64 corner segments, vector paths and their
// scalar twins).

#include "dsoc/visibility/shaft_occlusion.hpp"

#include "dsoc/visibility/reference_visibility.hpp"
#include "shaft_detail.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dsoc::visibility {

namespace {

using shaft_detail::corners;
using shaft_detail::kMaxBufferedPlanes;

} // namespace

bool shaft_blocked_by_box_scalar(const Aabb& region, const Aabb& box, const Aabb& solid) {
    if (region.is_empty() || box.is_empty() || solid.is_empty()) {
        return false;
    }
    // The answer of segment_through_box() for all 64 segments from a corner of the region
    // to a corner of the box, with the same floats, without walking them:
    // - On each axis a segment starts on the region's min or max side and ends on the
    //   box's min or max side; the four pairs of sides give every value that axis
    //   contributes (b - a, its inverse, the slab's entry and exit times), and the 64
    //   segments are every choice of one pair per axis.
    // - A segment passes when no flat axis (b - a = 0) starts outside the slab and
    //   fl(t1 - t0) > 1e-6 for t0 the max of 0 and its entries, t1 the min of 1 and its
    //   exits (segment_through_box() checks after each axis; t1 - t0 only shrinks).
    // - fl(u - v) is monotone in u and v, so that holds iff fl(u - v) > 1e-6 for every
    //   exit u and entry v of the segment: on one axis that is one pair of sides' own exit
    //   and entry, and across two axes any exit of one with any entry of the other. Hence
    //   the per-pair check below and, per two axes, the least exit against the largest
    //   entry. Entries are taken as max(0, entry) and exits as min(1, exit) (what t0 and
    //   t1 start from), which also drops a NaN as std::max and std::min do there.
    constexpr float kMinOverlap = 1.0e-6f; // segment_through_box()'s
    const glm::vec3 lo = solid.min + glm::vec3(kBoxShrink);
    const glm::vec3 hi = solid.max - glm::vec3(kBoxShrink);
    float largest_entry[3];
    float least_exit[3];
    for (int axis = 0; axis < 3; ++axis) {
        largest_entry[axis] = 0.0f;
        least_exit[axis] = 1.0f;
        for (int sides = 0; sides < 4; ++sides) {
            const float from = (sides & 1) != 0 ? region.max[axis] : region.min[axis];
            const float to = (sides & 2) != 0 ? box.max[axis] : box.min[axis];
            const float d = to - from;
            if (d == 0.0f) {
                if (!(from > lo[axis] && from < hi[axis])) {
                    return false; // these segments run outside the slab
                }
                continue; // the axis leaves their interval as it is
            }
            const float inv = 1.0f / d;
            float ta = (lo[axis] - from) * inv;
            float tb = (hi[axis] - from) * inv;
            if (ta > tb) {
                std::swap(ta, tb);
            }
            const float entry = std::max(0.0f, ta);
            const float exit = std::min(1.0f, tb);
            if (exit - entry <= kMinOverlap) {
                return false;
            }
            largest_entry[axis] = std::max(largest_entry[axis], entry);
            least_exit[axis] = std::min(least_exit[axis], exit);
        }
    }
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            if (a != b && least_exit[a] - largest_entry[b] <= kMinOverlap) {
                return false;
            }
        }
    }
    return true;
}

bool shaft_blocked_by_box(const Aabb& region, const Aabb& box, const Aabb& solid) {
#if defined(__SSE2__)
    if (region.is_empty() || box.is_empty() || solid.is_empty()) {
        return false;
    }
    // shaft_blocked_by_box_scalar()'s floats, its four pairs of sides of an axis in the
    // four lanes (lane s: the region's side s & 1, the box's side s & 2). IEEE division,
    // products and differences are the scalar ones, and each min and max below is
    // written to pick as the scalar std::min or std::max does, NaN included; the checks
    // are the same conjunction, in another order.
    constexpr float kMinOverlap = 1.0e-6f; // segment_through_box()'s
    const glm::vec3 lo = solid.min + glm::vec3(kBoxShrink);
    const glm::vec3 hi = solid.max - glm::vec3(kBoxShrink);
    const __m128 zero = _mm_setzero_ps();
    const __m128 one = _mm_set1_ps(1.0f);
    const __m128 min_overlap = _mm_set1_ps(kMinOverlap);
    float largest_entry[3];
    float least_exit[3];
    for (int axis = 0; axis < 3; ++axis) {
        const __m128 from =
            _mm_setr_ps(region.min[axis], region.max[axis], region.min[axis], region.max[axis]);
        const __m128 to = _mm_setr_ps(box.min[axis], box.min[axis], box.max[axis], box.max[axis]);
        const __m128 slab_lo = _mm_set1_ps(lo[axis]);
        const __m128 slab_hi = _mm_set1_ps(hi[axis]);
        const __m128 d = _mm_sub_ps(to, from);
        const __m128 flat = _mm_cmpeq_ps(d, zero);
        // A flat pair's segments run outside the slab unless they start inside it.
        const __m128 inside = _mm_and_ps(_mm_cmpgt_ps(from, slab_lo), _mm_cmplt_ps(from, slab_hi));
        if (_mm_movemask_ps(_mm_andnot_ps(inside, flat)) != 0) {
            return false;
        }
        // Flat lanes divide by zero (the flag is raised, no trap is enabled here) and
        // their results are not read.
        const __m128 inv = _mm_div_ps(one, d);
        const __m128 ta = _mm_mul_ps(_mm_sub_ps(slab_lo, from), inv);
        const __m128 tb = _mm_mul_ps(_mm_sub_ps(slab_hi, from), inv);
        const __m128 near = _mm_min_ps(tb, ta);      // ta > tb ? tb : ta
        const __m128 far = _mm_max_ps(ta, tb);       // ta > tb ? ta : tb
        const __m128 entry = _mm_max_ps(near, zero); // std::max(0.0f, near)
        const __m128 exit = _mm_min_ps(far, one);    // std::min(1.0f, far)
        const __m128 shut = _mm_cmple_ps(_mm_sub_ps(exit, entry), min_overlap);
        if (_mm_movemask_ps(_mm_andnot_ps(flat, shut)) != 0) {
            return false;
        }
        // Flat lanes leave the axis's interval as it is: entry 0, exit 1.
        __m128 e = _mm_andnot_ps(flat, entry);
        __m128 x = _mm_or_ps(_mm_and_ps(flat, one), _mm_andnot_ps(flat, exit));
        e = _mm_max_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(1, 0, 3, 2)));
        e = _mm_max_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(2, 3, 0, 1)));
        x = _mm_min_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(1, 0, 3, 2)));
        x = _mm_min_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 3, 0, 1)));
        largest_entry[axis] = _mm_cvtss_f32(e);
        least_exit[axis] = _mm_cvtss_f32(x);
    }
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            if (a != b && least_exit[a] - largest_entry[b] <= kMinOverlap) {
                return false;
            }
        }
    }
    return true;
#else
    return shaft_blocked_by_box_scalar(region, box, solid);
#endif
}

namespace {

/// shaft_blocked_by()'s answers before any segment: false for an empty box or solid,
/// and when a plane has every region corner and every box corner strictly outside it
/// (no segment between them crosses it).
bool not_blocked_at_once(const Aabb& region, const Aabb& box, std::span<const Plane> planes,
                         const std::array<glm::vec3, 8>& rc, const std::array<glm::vec3, 8>& bc) {
    if (region.is_empty() || box.is_empty() || planes.empty()) {
        return true;
    }
    for (const Plane& p : planes) {
        bool all_outside = true;
        for (const auto& c : rc) {
            all_outside = all_outside && p.signed_distance(c) >= 0.0f;
        }
        for (const auto& c : bc) {
            all_outside = all_outside && p.signed_distance(c) >= 0.0f;
        }
        if (all_outside) {
            return true;
        }
    }
    return false;
}

} // namespace

bool shaft_blocked_by_scalar(const Aabb& region, const Aabb& box, std::span<const Plane> planes) {
    const auto rc = corners(region);
    const auto bc = corners(box);
    if (not_blocked_at_once(region, box, planes, rc, bc)) {
        return false;
    }
    for (const auto& a : rc) {
        for (const auto& b : bc) {
            if (!segment_blocked_by(a, b, planes)) {
                return false;
            }
        }
    }
    return true;
}

bool shaft_blocked_by(const Aabb& region, const Aabb& box, std::span<const Plane> planes) {
#if defined(__SSE2__)
    // segment_blocked_by() for the 64 corner segments, two at a time, with its doubles:
    // - a segment's start term, dot(n, a) - d, depends on its region corner alone, and
    //   each product n[axis] * (b[axis] - a[axis]) of its rate, dot(n, b - a), on one
    //   side of the region and one of the box: each is worked out once (the starts per
    //   region corner, when its segments come up), by the same IEEE operations, and
    //   each rate is summed in glm::dot()'s order;
    // - the two lanes are the box's min and max x, for one region corner and one choice
    //   of the box's y and z sides;
    // - each min and max picks as the scalar std::min or std::max does, NaN included.
    // The answer is segment_blocked_by()'s for every segment: a segment's entry time
    // only rises and its exit time only falls, so neither the plane at which a segment
    // fails nor the segment that fails first changes it.
    constexpr std::size_t kMaxPlanes = kMaxBufferedPlanes;
    if (planes.size() > kMaxPlanes) {
        return shaft_blocked_by_scalar(region, box, planes);
    }
    const auto rc = corners(region);
    const auto bc = corners(box);
    if (not_blocked_at_once(region, box, planes, rc, bc)) {
        return false;
    }
    // The differences b[axis] - a[axis] per [region side][box side], then per plane the
    // products with the normal: the two x products side by side, the lanes.
    double diff[3][2][2];
    for (int axis = 0; axis < 3; ++axis) {
        for (int r = 0; r < 2; ++r) {
            for (int b = 0; b < 2; ++b) {
                diff[axis][r][b] =
                    static_cast<double>(b != 0 ? box.max[axis] : box.min[axis]) -
                    static_cast<double>(r != 0 ? region.max[axis] : region.min[axis]);
            }
        }
    }
    struct Terms {
        alignas(16) double rate_x[2][2];
        double rate_y[2][2];
        double rate_z[2][2];
    };
    std::array<Terms, kMaxPlanes> terms;
    for (std::size_t k = 0; k < planes.size(); ++k) {
        const glm::dvec3 n(planes[k].normal);
        for (int r = 0; r < 2; ++r) {
            for (int b = 0; b < 2; ++b) {
                terms[k].rate_x[r][b] = n.x * diff[0][r][b];
                terms[k].rate_y[r][b] = n.y * diff[1][r][b];
                terms[k].rate_z[r][b] = n.z * diff[2][r][b];
            }
        }
    }
    std::array<double, kMaxPlanes> start; // dot(n, a) - d per plane, for one region corner a
    const __m128d zero = _mm_setzero_pd();
    const __m128d one = _mm_set1_pd(1.0);
    const __m128d min_overlap = _mm_set1_pd(1.0e-6); // segment_blocked_by()'s
    const __m128d sign = _mm_set1_pd(-0.0);
    const __m128d all = _mm_castsi128_pd(_mm_set1_epi32(-1));
    for (int i = 0; i < 8; ++i) {
        const int rx = i & 1;
        const int ry = (i >> 1) & 1;
        const int rz = i >> 2;
        const glm::dvec3 a(rc[static_cast<std::size_t>(i)]);
        for (std::size_t k = 0; k < planes.size(); ++k) {
            start[k] =
                glm::dot(glm::dvec3(planes[k].normal), a) - static_cast<double>(planes[k].distance);
        }
        for (int yz = 0; yz < 4; ++yz) {
            const int by = yz & 1;
            const int bz = yz >> 1;
            __m128d enter = zero;
            __m128d exit = one;
            for (std::size_t k = 0; k < planes.size(); ++k) {
                const Terms& t = terms[k];
                const __m128d rate =
                    _mm_add_pd(_mm_add_pd(_mm_load_pd(t.rate_x[rx]), _mm_set1_pd(t.rate_y[ry][by])),
                               _mm_set1_pd(t.rate_z[rz][bz]));
                const __m128d from = _mm_set1_pd(start[k]);
                const __m128d flat = _mm_cmpeq_pd(rate, zero);
                if (_mm_movemask_pd(_mm_and_pd(flat, _mm_cmpge_pd(from, zero))) != 0) {
                    return false; // parallel and outside or on the plane
                }
                // Flat lanes divide by zero (no trap is enabled) and are not read.
                const __m128d at = _mm_div_pd(_mm_xor_pd(from, sign), rate); // -start / rate
                const __m128d entering = _mm_cmplt_pd(rate, zero);
                const __m128d leaving = _mm_andnot_pd(_mm_or_pd(flat, entering), all);
                const __m128d rise = _mm_and_pd(entering, _mm_cmplt_pd(enter, at));
                const __m128d fall = _mm_and_pd(leaving, _mm_cmplt_pd(at, exit));
                enter = _mm_or_pd(_mm_and_pd(rise, at), _mm_andnot_pd(rise, enter));
                exit = _mm_or_pd(_mm_and_pd(fall, at), _mm_andnot_pd(fall, exit));
                if (_mm_movemask_pd(_mm_cmple_pd(_mm_sub_pd(exit, enter), min_overlap)) != 0) {
                    return false;
                }
            }
        }
    }
    return true;
#else
    return shaft_blocked_by_scalar(region, box, planes);
#endif
}

} // namespace dsoc::visibility
