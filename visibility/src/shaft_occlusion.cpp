#include "dsoc/visibility/shaft_occlusion.hpp"

#include "dsoc/visibility/reference_visibility.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dsoc::visibility {

namespace {

/// Boxes up to kMaxPortalBoxSide: they get portal tests and witness searches.
bool small_box(const Aabb& b) {
    const glm::vec3 extent = b.size();
    return std::max(extent.x, std::max(extent.y, extent.z)) <= ShaftOcclusion::kMaxPortalBoxSide;
}

/// Corner k of `b`: bit 0 of k picks max x, bit 1 max y, bit 2 max z.
glm::vec3 corner(const Aabb& b, std::uint32_t k) {
    return {(k & 1u) ? b.max.x : b.min.x, (k & 2u) ? b.max.y : b.min.y,
            (k & 4u) ? b.max.z : b.min.z};
}

std::array<glm::vec3, 8> corners(const Aabb& b) {
    std::array<glm::vec3, 8> c;
    for (std::uint32_t k = 0; k < 8; ++k) {
        c[k] = corner(b, k);
    }
    return c;
}

/// Planes a solid may have for the buffers below (no brush has more; past it,
/// shaft_blocked_by() takes the scalar path and a witness counts the solid as in its way).
constexpr std::size_t kMaxBufferedPlanes = 32;

/// Does the segment from + t * dir, t in [0, 1], touch the closed box? `inv` is 1 / dir
/// per axis.
bool segment_hits_box(glm::vec3 from, glm::vec3 inv, const Aabb& box) {
    float t0 = 0.0f;
    float t1 = 1.0f;
    return clip_segment_to_box(from, inv, box, t0, t1);
}

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

namespace {

/// The hint naming the plane through the middle of occluder `id` across `axis`.
std::uint32_t portal_plane_hint(int axis, OccluderId id) {
    return ShaftOcclusion::kPortalHint | static_cast<std::uint32_t>(axis) << 29 | id;
}

} // namespace

Visibility ShaftOcclusion::test(const Aabb& region, const Aabb& box, Scratch& scratch,
                                std::uint32_t* hint) const {
    scratch.portal_budget = kPortalBudget;
    return test_at(region, box, scratch, hint, small_box(box) ? portal_depth_ : 0);
}

int ShaftOcclusion::hidden_through_portals(const Aabb& region, const Aabb& box, Scratch& scratch,
                                           int depth) const {
    const auto level = static_cast<std::size_t>(depth - 1);
    std::vector<CutPlane>& planes = scratch.portal_planes[level];
    std::vector<Aabb>& portals = scratch.portals[level];
    planes = scratch.planes; // the tests below reuse scratch.planes
    scratch.portal_sources[level] = scratch.plane_sources;
    const CutPlaneFusion fusion(*world_, *grid_);
    for (std::size_t pi = 0; pi < planes.size(); ++pi) {
        const CutPlane& plane = planes[pi];
        const CutPlaneFusion::Coverage cover =
            fusion.coverage(region, box, plane, scratch.grid, scratch.fusion, false);
        if (cover == CutPlaneFusion::Coverage::covered) {
            return static_cast<int>(pi); // the fused occluders alone close the plane
        }
        if (cover != CutPlaneFusion::Coverage::partial ||
            scratch.fusion.pieces.size() > kMaxPortals) {
            continue; // undecided, or too many open parts
        }
        const int a = plane.axis;
        const int u = (a + 1) % 3;
        const int v = (a + 2) % 3;
        portals.clear();
        for (const CutPlaneFusion::Polygon& piece : scratch.fusion.pieces) {
            glm::dvec2 lo;
            glm::dvec2 hi;
            CutPlaneFusion::bounds(piece, lo, hi);
            Aabb portal;
            portal.min[a] = portal.max[a] = plane.offset;
            portal.min[u] = static_cast<float>(lo.x) - kPortalPad;
            portal.min[v] = static_cast<float>(lo.y) - kPortalPad;
            portal.max[u] = static_cast<float>(hi.x) + kPortalPad;
            portal.max[v] = static_cast<float>(hi.y) + kPortalPad;
            portals.push_back(portal);
        }
        // Largest openings first: a box seen through one fails fastest there.
        std::sort(portals.begin(), portals.end(), [a](const Aabb& x, const Aabb& y) {
            const glm::vec3 sx = x.size();
            const glm::vec3 sy = y.size();
            return sx[(a + 1) % 3] * sx[(a + 2) % 3] > sy[(a + 1) % 3] * sy[(a + 2) % 3];
        });
        const auto closed = [&](const Aabb& portal, int sub_depth) {
            for (int side = 0; side < 2; ++side) {
                if (scratch.portal_budget <= 0) {
                    return false;
                }
                --scratch.portal_budget;
                // At sub_depth > 0 the cheap tests of this side already failed.
                const bool cheap_done = sub_depth > 0;
                const Visibility seen =
                    side == 0 ? test_at(region, portal, scratch, nullptr, sub_depth, cheap_done)
                              : test_at(portal, box, scratch, nullptr, sub_depth, cheap_done);
                if (seen == Visibility::occluded) {
                    return true;
                }
            }
            return false;
        };
        bool all_closed = true;
        for (const Aabb& portal : portals) {
            // The cheap tests of both sides before the deeper ones.
            if (closed(portal, 0) || (depth > 1 && closed(portal, depth - 1))) {
                continue;
            }
            all_closed = false;
            break;
        }
        if (all_closed) {
            return static_cast<int>(pi);
        }
    }
    return -1;
}

bool ShaftOcclusion::segment_clear(glm::vec3 a, glm::vec3 b, Scratch& scratch) const {
    // Every occluder grown by kWitnessMargin: its bounds and axis box on every side, its
    // planes moved out (by the margin for unit normals, as brushes have).
    constexpr float m = kWitnessMargin;
    const SegmentRay ray = SegmentRay::between(a, b);
    const auto grown = [](const Aabb& box) {
        return Aabb{box.min - glm::vec3(m), box.max + glm::vec3(m)};
    };
    return !grid_->any_along_segment(a, b, scratch.grid, [&](OccluderId id) {
        if (!segment_hits_box(a, ray.inv, grown(world_->occluder(id).bounds()))) {
            return false;
        }
        const Aabb& solid = world_->solid_box(id);
        if (!solid.is_empty()) {
            return segment_hits_box(a, ray.inv, grown(solid));
        }
        const std::span<const Plane> planes = world_->solid_planes(id);
        std::array<Plane, kMaxBufferedPlanes> moved;
        if (planes.size() > moved.size()) {
            return true;
        }
        for (std::size_t k = 0; k < planes.size(); ++k) {
            moved[k] = {planes[k].normal, planes[k].distance + m};
        }
        return segment_blocked_by(a, b, std::span<const Plane>(moved.data(), planes.size()));
    });
}

std::uint32_t ShaftOcclusion::find_witness(const Aabb& region, const Aabb& box,
                                           Scratch& scratch) const {
    // Two segments beside the centre one, above it: from the region's upper corners to
    // the box's same corners (entities stand on floors, and what blocks the centre is
    // mostly an edge below the line of sight). Two corners find nearly every witness
    // four do, for half the walks.
    static constexpr std::array<std::uint32_t, 2> kCorners = {6, 7};
    for (const std::uint32_t k : kCorners) {
        if (segment_clear(corner(region, k), corner(box, k), scratch)) {
            return kWitnessHint | k << 3 | k;
        }
    }
    return 0;
}

Visibility ShaftOcclusion::test_at(const Aabb& region, const Aabb& box, Scratch& scratch,
                                   std::uint32_t* hint, int depth, bool cheap_done) const {
    if (region.is_empty() || box.is_empty() || region.overlaps(box)) {
        return Visibility::visible;
    }
    // Temporal coherence for boxes in view: last time's clear segment, if still clear
    // (of every occluder by kWitnessMargin), shows this box visible too: the exact
    // answer, since every proof below would fail.
    // A record of a failed search (kNoWitness) is kept aside for the end.
    std::uint32_t no_witness = 0;
    if (hint != nullptr && !cheap_done &&
        (*hint & ~(kNoWitness | kWitnessCorners)) == kWitnessHint) {
        if ((*hint & kNoWitness) != 0) {
            no_witness = *hint;
        } else {
            if (segment_clear(corner(region, (*hint >> 3) & 7u), corner(box, *hint & 7u),
                              scratch)) {
                return Visibility::visible; // the hint stays
            }
        }
        *hint = 0;
    }
    const auto blocks_shaft = [&](OccluderId id) {
        const Aabb& solid = world_->solid_box(id);
        return solid.is_empty() ? shaft_blocked_by(region, box, world_->solid_planes(id))
                                : shaft_blocked_by_box(region, box, solid);
    };
    const auto separates = [&](const CutPlane& plane) {
        const int axis = plane.axis;
        return (region.max[axis] < plane.offset && box.min[axis] > plane.offset) ||
               (region.min[axis] > plane.offset && box.max[axis] < plane.offset);
    };
    const auto mid_plane = [&](OccluderId id, int axis) {
        const Aabb& ob = world_->occluder(id).bounds();
        return CutPlane{axis, 0.5f * (ob.min[axis] + ob.max[axis])};
    };
    // Temporal coherence for boxes the portal tests failed to hide last time (most of
    // them visible): skip those tests for the next few queries (answering `visible` is
    // always allowed), counting down in the hint.
    std::uint32_t skips_left = 0;
    if (hint != nullptr && (*hint & kPortalHint) != 0 && ((*hint >> 29) & 3u) == 3u) {
        skips_left = std::min<std::uint32_t>(*hint & ((1u << 29) - 1), kPortalSkips);
        *hint = 0;
    }
    const bool skip_portals = skips_left > 0;
    // Temporal coherence: a fusion or portal proof on the same plane as last time.
    bool hinted_plane_failed = false;
    CutPlane hinted_plane;
    if (hint != nullptr && (*hint & kPortalHint) != 0 && fusion_ && !cheap_done) {
        const OccluderId id = *hint & ((1u << 29) - 1);
        const int axis = static_cast<int>((*hint >> 29) & 3u);
        *hint = 0;
        if (id < world_->size() && axis < 3 && separates(mid_plane(id, axis))) {
            hinted_plane = mid_plane(id, axis);
            // With portal levels left, one coverage of the plane decides both: covered
            // (fusion) or every open part closed (portals).
            bool proved = false;
            if (depth > 0) {
                scratch.planes.assign(1, hinted_plane);
                scratch.plane_sources.assign(1, id);
                proved = hidden_through_portals(region, box, scratch, depth) >= 0;
                scratch.portal_budget = kPortalBudget; // the full test below gets its own
            } else {
                proved = CutPlaneFusion(*world_, *grid_)
                             .covers(region, box, hinted_plane, scratch.grid, scratch.fusion);
            }
            if (proved) {
                *hint = portal_plane_hint(axis, id);
                return Visibility::occluded;
            }
            hinted_plane_failed = true;
        }
    }
    // Temporal coherence: the occluder that hid this box last time usually still does.
    OccluderId tried = OccluderWorld::kInvalid; // already tested: skipped below
    if (hint != nullptr && *hint != 0 && !cheap_done) {
        const OccluderId id = *hint - 1;
        if (id < world_->size() && blocks_shaft(id)) {
            return Visibility::occluded;
        }
        tried = id;
        *hint = 0;
    }
    const glm::vec3 from = region.center();
    const glm::vec3 to = box.center();
    int full_tests = 0;
    scratch.planes.clear();
    scratch.plane_sources.clear();
    // Occluders that touch or cut into the region count too: the corner argument
    // holds for any convex solid (an eye inside a wall is no eye, and its segments
    // do pass through the wall's interior).
    const SegmentRay centre = SegmentRay::between(from, to);
    const auto add_plane = [&](OccluderId id, int axis) {
        const CutPlane plane = mid_plane(id, axis);
        if (separates(plane) && scratch.planes.size() < kMaxCutPlanes &&
            std::find(scratch.planes.begin(), scratch.planes.end(), plane) ==
                scratch.planes.end()) {
            scratch.planes.push_back(plane);
            scratch.plane_sources.push_back(id);
        }
    };
    // Only an occluder that blocks the centre-to-centre segment can pass the first
    // check below, and such an occluder lies in a cell that segment crosses. They are
    // taken as the walk along it finds them, nearest cells first, and the walk ends at
    // the first that hides the box (or at kMaxFullTests): the rest of a long segment
    // (across a city, say) is not walked for nothing.
    bool one_hides = false;
    bool centre_blocked = false;
    grid_->any_along_segment(from, to, scratch.grid, [&](OccluderId id) {
        const Aabb& ob = world_->occluder(id).bounds();
        if (!segment_hits_box(from, centre.inv, ob)) {
            return false; // misses the occluder's bounds, so it cannot block the segment
        }
        if (full_tests >= kMaxFullTests) {
            return true; // no further single occluder is tried
        }
        // Necessary condition, one segment: the occluder must block centre to centre
        // (also for fusion: some occluder's interior holds the centre's crossing).
        const Aabb& solid = world_->solid_box(id); // non-empty: an axis box (fast path)
        if (!(solid.is_empty() ? segment_blocked_by(from, to, world_->solid_planes(id))
                               : segment_through_box(centre, solid))) {
            return false;
        }
        centre_blocked = true;
        if (!cheap_done && id != tried && blocks_shaft(id)) {
            if (hint != nullptr) {
                *hint = id + 1;
            }
            one_hides = true;
            return true;
        }
        ++full_tests;
        if (fusion_) {
            // Through the wall's middle (planes just inside its faces as well were
            // measured: on oa_dm4 they add 1% culled for 50% more fusion time).
            for (int axis = 0; axis < 3; ++axis) {
                add_plane(id, axis);
            }
        }
        return false;
    });
    if (one_hides) {
        return Visibility::occluded;
    }
    if (!scratch.planes.empty()) {
        const CutPlaneFusion fusion(*world_, *grid_);
        for (std::size_t i = 0; !cheap_done && i < scratch.planes.size(); ++i) {
            if (hinted_plane_failed && scratch.planes[i] == hinted_plane) {
                continue; // just failed above
            }
            if (fusion.covers(region, box, scratch.planes[i], scratch.grid, scratch.fusion)) {
                if (hint != nullptr) {
                    *hint = portal_plane_hint(scratch.planes[i].axis, scratch.plane_sources[i]);
                }
                return Visibility::occluded;
            }
        }
        if (hinted_plane_failed) { // its fusion and portal tests just failed: not twice
            for (std::size_t i = 0; i < scratch.planes.size(); ++i) {
                if (scratch.planes[i] == hinted_plane) {
                    scratch.planes.erase(scratch.planes.begin() + static_cast<std::ptrdiff_t>(i));
                    scratch.plane_sources.erase(scratch.plane_sources.begin() +
                                                static_cast<std::ptrdiff_t>(i));
                    break;
                }
            }
        }
        if (depth > 0 && !skip_portals && !scratch.planes.empty()) {
            const int proved = hidden_through_portals(region, box, scratch, depth);
            if (proved >= 0) {
                if (hint != nullptr) {
                    // The portal tests kept this level's planes (scratch.planes is reused).
                    const auto level = static_cast<std::size_t>(depth - 1);
                    const auto k = static_cast<std::size_t>(proved);
                    *hint = portal_plane_hint(scratch.portal_planes[level][k].axis,
                                              scratch.portal_sources[level][k]);
                }
                return Visibility::occluded;
            }
            skips_left = kPortalSkips + 1; // the portal tests failed: skip the next ones
        }
    }
    if (hint != nullptr && skips_left > 1) {
        *hint = kPortalHint | 3u << 29 | (skips_left - 1);
    } else if (hint != nullptr && centre_blocked && !cheap_done && small_box(box)) {
        // Visible, yet the centre segment is blocked: a clear segment beside it spares
        // the next test these failed proofs (none is looked for when the centre is
        // clear: the next test walks it first), unless searches keep failing. Not for
        // large boxes (entity clusters, TBVs), whose hints are not kept while visible.
        const std::uint32_t level = (no_witness >> 4) & 3u;
        const std::uint32_t skips = no_witness & 15u;
        if (no_witness != 0 && skips > 0) {
            *hint = kWitnessHint | kNoWitness | level << 4 | (skips - 1);
        } else if (const std::uint32_t found = find_witness(region, box, scratch); found != 0) {
            *hint = found;
        } else {
            const std::uint32_t next = no_witness != 0 ? std::min(level + 1, 3u) : 0u;
            *hint = kWitnessHint | kNoWitness | next << 4 | ((2u << next) - 1);
        }
    }
    return Visibility::visible;
}

} // namespace dsoc::visibility
