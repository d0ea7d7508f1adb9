#pragma once
// Quake 3's curved surfaces ("patches"): a grid of control points read as biquadratic
// Bezier patches of 3 x 3 points that share their edges. The game draws them (a
// pillar's round face, an arch); the occluders leave them out (map.hpp), but what the
// game draws opaque blocks sight all the same, so the evaluation's ray oracle takes
// them as triangles.

#include <glm/vec3.hpp>

#include <vector>

namespace dsoc::maps {

/// A curved surface drawn with a shader that does not let sight through. Both sizes
/// are odd, from 3 to q3::kMaxPatchSide, and every point is finite (the loader checks).
struct CurvedSurface {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> points; ///< row by row: points[row * width + column]
};

/// Appends the surface as triangles (three points each) to `triangles`: each 3 x 3
/// patch evaluated on a `steps` x `steps` grid of its parameters (steps >= 1), two
/// triangles a grid square. The grid passes through the patch's corners and its edge
/// curves at every step, so neighbouring patches meet without gaps. Between grid points
/// a triangle departs from the curved surface by at most |P''| / (8 steps^2) along each
/// parameter (P'' = 2 (p0 - 2 p1 + p2) of the control row): under 0.1 units at 16 steps
/// for an arc of a 64-unit radius.
void tessellate(const CurvedSurface& surface, int steps, std::vector<glm::vec3>& triangles);

} // namespace dsoc::maps
