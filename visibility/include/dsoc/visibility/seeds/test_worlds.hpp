#pragma once
// Small synthetic occluder worlds for tests and benchmarks (the real map loaders
// live in dsoc::maps). Deterministic for a given seed on a given standard library.
// Not on the server's path: the tests and visibility_bench use them.

#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>

namespace dsoc::visibility {

/// A generated world for tests and benchmarks; not meant for a game server (use
/// dsoc::maps to load real maps).
struct TestWorld {
    OccluderWorld world;
    /// Where eyes and test boxes are meant to be placed (walkable space plus some
    /// height); points inside it may still be inside an occluder.
    Aabb play_area;
};

/// A `rooms_x` x `rooms_y` grid of rooms (512 units square, 256 high) joined by
/// doorways, with a floor slab, crates and pillars: about 10 brushes per room.
/// 10 x 10 rooms give ~1,000 brushes. Some pillars are rotated (non-axis-aligned).
[[nodiscard]] TestWorld make_corridor_world(std::uint32_t seed, int rooms_x, int rooms_y);

/// City blocks: a grid of buildings of random height (some with sloped roofs) along
/// streets 192 units wide.
[[nodiscard]] TestWorld make_city_world(std::uint32_t seed, int blocks_x, int blocks_y);

/// `count` random convex brushes (boxes, rotated boxes, boxes cut by random planes)
/// of 8..256 units in a cube of side `extent`.
[[nodiscard]] TestWorld make_random_world(std::uint32_t seed, int count, float extent);

/// `count` long thin walls (8..32 thick, 128..1024 long, 64..512 high) at random
/// orientations about the vertical axis, in a square of side `extent`.
[[nodiscard]] TestWorld make_walls_world(std::uint32_t seed, int count, float extent);

/// A box rotated by `yaw` radians about +z around its centre, as a polyhedron.
[[nodiscard]] ConvexPolyhedron make_rotated_box(glm::vec3 center, glm::vec3 half_extents,
                                                float yaw);

} // namespace dsoc::visibility
