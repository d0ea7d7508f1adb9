#pragma once
// Occluder fusion from a region, across an axis-aligned cut plane.
//
// Let the plane x[axis] = c separate a box of eyes R from a box B (R wholly on one
// side, B wholly on the other, neither touching the plane). Every segment from a
// point of R to a point of B crosses the plane exactly once, inside S: the bounding
// rectangle of the points where the 64 segments joining R's corners to B's corners
// cross it (the shaft hull(R u B) meets the plane in the convex hull of those points;
// the rectangle contains it). A point of the plane inside a convex occluder is a point
// of the segment inside that occluder. So when the occluders the plane cuts cover S
// between them, every segment from R to B passes through some occluder: B is hidden
// from every eye of R. Coverage is decided exactly, by subtracting each occluder's
// cross-section (a convex polygon) from S, so a wall built from many brushes of any
// thickness - a door frame, a pillar against a wall, a floor of tiles - blocks as one,
// which the single-occluder shaft test (shaft_occlusion.hpp) cannot do.
//
// Limits: pieces of S left uncovered that are narrower than kNoiseWidth (1e-3 unit:
// float rounding of the planes of two brushes that share a face) count as covered;
// past kMaxPieces uncovered pieces or kMaxOccluders cut occluders the answer is
// "not covered" (always allowed).

#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_grid.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <glm/vec2.hpp>

#include <algorithm>
#include <array>
#include <vector>

namespace dsoc::visibility {

/// The plane x[axis] = offset (axis 0, 1, 2 for x, y, z; offset in world units).
struct CutPlane {
    int axis = 0;
    float offset = 0.0f;
    friend bool operator==(const CutPlane&, const CutPlane&) = default;
};

class CutPlaneFusion {
public:
    /// `world` and `grid` (built over `world`) must outlive this.
    CutPlaneFusion(const OccluderWorld& world, const OccluderGrid& grid)
        : world_(&world), grid_(&grid) {}

    /// A convex polygon in the plane's two other axes (double: the subtraction of
    /// many brushes must not open gaps at shared faces).
    struct Polygon {
        static constexpr int kCapacity = 40;
        std::array<glm::dvec2, kCapacity> v;
        int n = 0;

        Polygon() = default;
        // Copies carry the n vertices in use, not the whole capacity: the subtraction
        // copies pieces of a few vertices many times per test.
        Polygon(const Polygon& other) : n(other.n) { std::copy_n(other.v.begin(), n, v.begin()); }
        Polygon& operator=(const Polygon& other) {
            n = other.n;
            std::copy_n(other.v.begin(), n, v.begin());
            return *this;
        }
    };
    /// Per-thread memory, reused between calls.
    struct Scratch {
        std::vector<Polygon> pieces;
        std::vector<Polygon> next;
        std::vector<std::pair<double, OccluderId>> cut; ///< (overlap area, occluder)
    };

    /// True only when `plane` separates `region` from `box` and the occluders it cuts
    /// cover S (see above): then every segment from a point of `region` to a point of
    /// `box` passes through an occluder's interior. False otherwise (which promises
    /// nothing). Const and thread-safe given per-thread scratches.
    [[nodiscard]] bool covers(const Aabb& region, const Aabb& box, CutPlane plane,
                              OccluderGrid::Scratch& grid_scratch, Scratch& scratch) const {
        return coverage(region, box, plane, grid_scratch, scratch, true) == Coverage::covered;
    }

    enum class Coverage {
        covered,   ///< the cut occluders cover S (what covers() answers true for)
        partial,   ///< scratch.pieces holds the parts of S they leave uncovered
        undecided, ///< a limit or a quick rejection: nothing is promised
    };
    /// What covers() decides, and when S is not covered the uncovered rest of S:
    /// `partial` leaves in `scratch.pieces` convex polygons (in the plane's (u, v)
    /// axes) whose union contains every point of S that no cut occluder's interior
    /// holds, so every segment from `region` to `box` either passes through an
    /// occluder at the plane or crosses it inside one of the pieces. `quick` allows
    /// cheap rejections (S's corners, total overlap) that answer `undecided` early;
    /// without it the pieces are computed whenever the limits allow.
    [[nodiscard]] Coverage coverage(const Aabb& region, const Aabb& box, CutPlane plane,
                                    OccluderGrid::Scratch& grid_scratch, Scratch& scratch,
                                    bool quick) const;

    /// The rectangle S in the plane's (u, v) axes (u = (axis+1)%3, v = (axis+2)%3), or
    /// false when the plane does not strictly separate region and box.
    [[nodiscard]] static bool crossing_rectangle(const Aabb& region, const Aabb& box,
                                                 CutPlane plane, glm::dvec2& lo, glm::dvec2& hi);

    /// The bounding rectangle of `poly` in its (u, v) axes.
    static void bounds(const Polygon& poly, glm::dvec2& lo, glm::dvec2& hi);

    /// True for an empty polygon, or one narrower than kNoiseWidth by twice its area
    /// over its perimeter (the width of a thin sliver): such a piece of S counts as
    /// covered. Decided without square roots where bounds on the perimeter allow; the
    /// same answer, bit for bit, as the perimeter's edge lengths summed.
    [[nodiscard]] static bool negligible(const Polygon& poly);

    static constexpr double kNoiseWidth = 1e-3;
    static constexpr std::size_t kMaxPieces = 64;
    static constexpr std::size_t kMaxOccluders = 64;

private:
    const OccluderWorld* world_;
    const OccluderGrid* grid_;
};

} // namespace dsoc::visibility
