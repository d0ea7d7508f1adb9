// ShaftOcclusion: the shaft stage over a world (single occluders along the centre
// segment, fusion on cut planes, portal tests, and the hints that carry one test's
// findings to the next).

#include "dsoc/visibility/shaft_occlusion.hpp"

#include "dsoc/visibility/occluder_bvh.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "shaft_detail.hpp"

#include <algorithm>
#include <array>

namespace dsoc::visibility {

namespace {

using shaft_detail::corner;
using shaft_detail::kMaxBufferedPlanes;
using shaft_detail::segment_hits_box;

/// Boxes up to kMaxPortalBoxSide: they get portal tests and witness searches.
bool small_box(const Aabb& b) {
    const glm::vec3 extent = b.size();
    return std::max(extent.x, std::max(extent.y, extent.z)) <= ShaftOcclusion::kMaxPortalBoxSide;
}

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
    // An occluder whose grown bounds the segment touches: is its grown solid in the way?
    const auto in_the_way = [&](OccluderId id) {
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
    };
    // The tree offers exactly the occluders whose grown bounds the segment touches (the
    // same floats as grown() and segment_hits_box()). The grid walk offers those in the
    // cells the segment crosses, and so may miss one that lies within the margin of the
    // segment in a cell it does not cross (beyond the grid's extent, or across a cell's
    // side): then a witness may pass closer than the margin to it. That costs only
    // tightness (a witness answers `visible`), and only without a tree.
    if (bvh_ != nullptr) {
        return !bvh_->any_touching_segment(a, b, in_the_way, m);
    }
    return !grid_->any_along_segment(a, b, scratch.grid, [&](OccluderId id) {
        return segment_hits_box(a, ray.inv, grown(world_->occluder(id).bounds())) && in_the_way(id);
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
    // A hint of 0: the last test of this pair left nothing to try first (it ended
    // visible with no witness or record kept: a clear centre segment, most often). Then
    // the tree checks the centre first, below; its answer is exact whatever the state.
    const bool tree_first = hint != nullptr && *hint == 0;
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
    // No occluder blocks the centre segment: then none can hide the box alone, and
    // fusion and portals have no plane to try, so the walk below would answer `visible`
    // and leave the hint as it is. The tree proves that without walking every grid cell
    // along the segment (it offers every occluder whose bounds the walk's test finds the
    // segment touching), for pairs whose last test left the hint 0, and for segments
    // longer than kMinTreeCells in tests without a hint (the portals' sub-tests, whose
    // short segments are cheap to walk). The others, whose last test found the centre
    // blocked, go to the walk directly. Whichever is asked, the answers are the walk's.
    const auto blocks_centre = [&](OccluderId id) {
        const Aabb& solid = world_->solid_box(id); // non-empty: an axis box (fast path)
        return solid.is_empty() ? segment_blocked_by(from, to, world_->solid_planes(id))
                                : segment_through_box(centre, solid);
    };
    const auto long_segment = [&] {
        const glm::vec3 span = glm::abs(to - from);
        return span.x + span.y + span.z > kMinTreeCells * grid_->cell_size();
    };
    if (bvh_ != nullptr && (tree_first || (hint == nullptr && long_segment())) &&
        !bvh_->any_touching_segment(from, to, blocks_centre)) {
        return Visibility::visible;
    }
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
        if (!blocks_centre(id)) {
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
