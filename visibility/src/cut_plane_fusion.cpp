#include "dsoc/visibility/cut_plane_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dsoc::visibility {

namespace {

using Polygon = CutPlaneFusion::Polygon;

/// A half-plane { p : dot(n, p) <= d } of the cut plane.
struct HalfPlane {
    glm::dvec2 n;
    double d;
};

/// Sutherland-Hodgman against one half-plane, both sides in one pass: `inside` keeps
/// dot(n, p) <= d, `outside` dot(n, p) >= d (each exactly what a clip against that side
/// alone gives: a vertex on the line goes to both, a crossing's point is computed once).
/// False when a result would not fit a Polygon (the caller gives up: "not covered").
bool split(const Polygon& in, const HalfPlane& h, Polygon& inside, Polygon& outside) {
    inside.n = 0;
    outside.n = 0;
    if (in.n == 0) {
        return true;
    }
    std::array<double, Polygon::kCapacity> distance;
    for (int i = 0; i < in.n; ++i) {
        distance[static_cast<std::size_t>(i)] =
            glm::dot(h.n, in.v[static_cast<std::size_t>(i)]) - h.d;
    }
    const auto put = [](Polygon& poly, const glm::dvec2& p) {
        if (poly.n == Polygon::kCapacity) {
            return false;
        }
        poly.v[static_cast<std::size_t>(poly.n++)] = p;
        return true;
    };
    for (int i = 0; i < in.n; ++i) {
        const int j = i + 1 == in.n ? 0 : i + 1;
        const glm::dvec2& p = in.v[static_cast<std::size_t>(i)];
        const glm::dvec2& q = in.v[static_cast<std::size_t>(j)];
        const double dp = distance[static_cast<std::size_t>(i)];
        const double dq = distance[static_cast<std::size_t>(j)];
        if ((dp <= 0.0 && !put(inside, p)) || (dp >= 0.0 && !put(outside, p))) {
            return false;
        }
        if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) {
            const double t = dp / (dp - dq);
            const glm::dvec2 crossing = p + (q - p) * t;
            if (!put(inside, crossing) || !put(outside, crossing)) {
                return false;
            }
        }
    }
    if (inside.n < 3) {
        inside.n = 0;
    }
    if (outside.n < 3) {
        outside.n = 0;
    }
    return true;
}

} // namespace

bool CutPlaneFusion::negligible(const Polygon& poly) {
    if (poly.n < 3) {
        return true;
    }
    double area2 = 0.0;
    // The perimeter's edges measured as |dx| + |dy|: at least each edge's length and at
    // most sqrt(2) times it, so it decides most pieces without a square root.
    double perimeter_l1 = 0.0;
    for (int i = 0; i < poly.n; ++i) {
        const glm::dvec2& p = poly.v[static_cast<std::size_t>(i)];
        const glm::dvec2& q = poly.v[static_cast<std::size_t>(i + 1 == poly.n ? 0 : i + 1)];
        area2 += p.x * q.y - q.x * p.y;
        perimeter_l1 += std::abs(q.x - p.x) + std::abs(q.y - p.y);
    }
    const double width2 = std::abs(area2);
    // Decided by the bounds only with a relative margin far above the rounding of either
    // sum, so the answer is the one the true perimeter gives below, bit for bit.
    constexpr double kMargin = 1.0 + 1e-9;
    if (perimeter_l1 > 0.0 && width2 >= CutPlaneFusion::kNoiseWidth * perimeter_l1 * kMargin) {
        return false; // wider by the longer measure, so by the true one too
    }
    if (width2 * std::sqrt(2.0) * kMargin < CutPlaneFusion::kNoiseWidth * perimeter_l1) {
        return true; // narrower even by the shortest measure the true perimeter allows
    }
    double perimeter = 0.0;
    for (int i = 0; i < poly.n; ++i) {
        const glm::dvec2& p = poly.v[static_cast<std::size_t>(i)];
        const glm::dvec2& q = poly.v[static_cast<std::size_t>(i + 1 == poly.n ? 0 : i + 1)];
        perimeter += glm::length(q - p);
    }
    return perimeter <= 0.0 || width2 / perimeter < CutPlaneFusion::kNoiseWidth;
}

namespace {

void bounds_of(const Polygon& poly, glm::dvec2& lo, glm::dvec2& hi) {
    lo = hi = poly.v[0];
    for (int i = 1; i < poly.n; ++i) {
        lo = glm::min(lo, poly.v[static_cast<std::size_t>(i)]);
        hi = glm::max(hi, poly.v[static_cast<std::size_t>(i)]);
    }
}

} // namespace

bool CutPlaneFusion::crossing_rectangle(const Aabb& region, const Aabb& box, CutPlane plane,
                                        glm::dvec2& lo, glm::dvec2& hi) {
    const int a = plane.axis;
    const double c = plane.offset;
    const bool region_below = region.max[a] < c && box.min[a] > c;
    const bool region_above = region.min[a] > c && box.max[a] < c;
    if (!region_below && !region_above) {
        return false;
    }
    const int u = (a + 1) % 3;
    const int v = (a + 2) % 3;
    lo = glm::dvec2(std::numeric_limits<double>::infinity());
    hi = -lo;
    // The crossing of r + t (b - r) is linear in r and b with positive weights for a
    // fixed t, so per t the extremes come from the min (max) corners; t takes its
    // extremes at the four combinations of the two boxes' faces on the axis.
    for (const double ra : {double{region.min[a]}, double{region.max[a]}}) {
        for (const double ba : {double{box.min[a]}, double{box.max[a]}}) {
            const double t = (c - ra) / (ba - ra);
            const double s = 1.0 - t;
            lo.x = std::min(lo.x, s * region.min[u] + t * box.min[u]);
            lo.y = std::min(lo.y, s * region.min[v] + t * box.min[v]);
            hi.x = std::max(hi.x, s * region.max[u] + t * box.max[u]);
            hi.y = std::max(hi.y, s * region.max[v] + t * box.max[v]);
        }
    }
    return true;
}

void CutPlaneFusion::bounds(const Polygon& poly, glm::dvec2& lo, glm::dvec2& hi) {
    bounds_of(poly, lo, hi);
}

CutPlaneFusion::Coverage CutPlaneFusion::coverage(const Aabb& region, const Aabb& box,
                                                  CutPlane plane,
                                                  OccluderGrid::Scratch& grid_scratch,
                                                  Scratch& scratch, bool quick) const {
    scratch.pieces.clear();
    if (region.is_empty() || box.is_empty()) {
        return Coverage::undecided;
    }
    glm::dvec2 lo;
    glm::dvec2 hi;
    if (!crossing_rectangle(region, box, plane, lo, hi)) {
        return Coverage::undecided;
    }
    const int a = plane.axis;
    const int u = (a + 1) % 3;
    const int v = (a + 2) % 3;
    const double c = plane.offset;

    // Necessary, and cheap before gathering: each corner of S lies in the bounds of an
    // occluder the plane cuts (a cross-section lies within its occluder's bounds).
    for (int k = 0; quick && k < 4; ++k) {
        glm::vec3 corner;
        corner[a] = plane.offset;
        corner[u] = static_cast<float>((k & 1) ? hi.x : lo.x);
        corner[v] = static_cast<float>((k & 2) ? hi.y : lo.y);
        bool inside = false;
        for (const OccluderId id : grid_->items_at(corner)) {
            const Aabb& ob = world_->occluder(id).bounds();
            if (ob.min[a] < plane.offset && ob.max[a] > plane.offset && ob.min[u] <= corner[u] &&
                ob.max[u] >= corner[u] && ob.min[v] <= corner[v] && ob.max[v] >= corner[v]) {
                inside = true;
                break;
            }
        }
        if (!inside) {
            return Coverage::undecided;
        }
    }
    // Occluders the plane cuts (strictly: their bounds straddle it) over S.
    Aabb query;
    query.min[a] = query.max[a] = plane.offset;
    query.min[u] = static_cast<float>(lo.x);
    query.max[u] = static_cast<float>(hi.x);
    query.min[v] = static_cast<float>(lo.y);
    query.max[v] = static_cast<float>(hi.y);
    grid_->query(query, grid_scratch);
    scratch.cut.clear();
    double overlap_sum = 0.0;
    for (const OccluderId id : grid_scratch.found) {
        const Aabb& ob = world_->occluder(id).bounds();
        if (!(ob.min[a] < plane.offset && ob.max[a] > plane.offset)) {
            continue;
        }
        const double w = std::min<double>(hi.x, ob.max[u]) - std::max<double>(lo.x, ob.min[u]);
        const double h = std::min<double>(hi.y, ob.max[v]) - std::max<double>(lo.y, ob.min[v]);
        if (w <= 0.0 || h <= 0.0) {
            continue;
        }
        scratch.cut.emplace_back(w * h, id);
        overlap_sum += w * h;
    }
    // The union cannot cover S when even the bounds' overlaps add up to less.
    const glm::dvec2 extent = hi - lo;
    if (quick && overlap_sum + 2.0 * kNoiseWidth * (extent.x + extent.y) < extent.x * extent.y) {
        return Coverage::undecided;
    }
    // Largest first: a wall's big brushes leave few pieces for the small ones.
    std::sort(scratch.cut.begin(), scratch.cut.end(),
              [](const auto& x, const auto& y) { return x.first > y.first; });
    if (scratch.cut.size() > kMaxOccluders) {
        scratch.cut.resize(kMaxOccluders); // fewer occluders can only cover less
    }

    Polygon rect;
    rect.n = 4;
    rect.v[0] = {lo.x, lo.y};
    rect.v[1] = {hi.x, lo.y};
    rect.v[2] = {hi.x, hi.y};
    rect.v[3] = {lo.x, hi.y};
    scratch.pieces.assign(1, rect);

    std::array<HalfPlane, 64> halves;
    Polygon rest;
    Polygon inside;
    Polygon outside;
    for (const auto& [area, id] : scratch.cut) {
        // The occluder's cross-section as half-planes of (u, v); a plane parallel to the
        // cut must have the cut strictly inside it, else the section is empty.
        std::size_t count = 0;
        bool empty = false;
        for (const Plane& p : world_->solid_planes(id)) {
            const double rhs = double{p.distance} - double{p.normal[a]} * c;
            const glm::dvec2 n(p.normal[u], p.normal[v]);
            if (std::abs(n.x) < 1e-9 && std::abs(n.y) < 1e-9) {
                empty = empty || rhs <= 0.0;
                continue;
            }
            if (count == halves.size()) {
                empty = true; // too many planes to use: skip the occluder (covers less)
                break;
            }
            halves[count++] = {n, rhs};
        }
        if (empty || count == 0) {
            continue;
        }
        const Aabb& ob = world_->occluder(id).bounds();
        const glm::dvec2 olo(ob.min[u], ob.min[v]);
        const glm::dvec2 ohi(ob.max[u], ob.max[v]);
        scratch.next.clear();
        for (const Polygon& piece : scratch.pieces) {
            glm::dvec2 plo;
            glm::dvec2 phi;
            bounds_of(piece, plo, phi);
            if (phi.x <= olo.x || plo.x >= ohi.x || phi.y <= olo.y || plo.y >= ohi.y) {
                scratch.next.push_back(piece); // untouched by this occluder
                continue;
            }
            // piece \ section = union over i of piece n (outside half i) n (inside halves < i).
            rest = piece;
            for (std::size_t i = 0; i < count && rest.n > 0; ++i) {
                if (!split(rest, halves[i], inside, outside)) {
                    return Coverage::undecided;
                }
                if (!negligible(outside)) {
                    scratch.next.push_back(outside);
                }
                rest = inside;
            }
            if (scratch.next.size() > kMaxPieces) {
                return Coverage::undecided;
            }
        }
        scratch.pieces.swap(scratch.next);
        if (scratch.pieces.empty()) {
            return Coverage::covered;
        }
    }
    return scratch.pieces.empty() ? Coverage::covered : Coverage::partial;
}

} // namespace dsoc::visibility
