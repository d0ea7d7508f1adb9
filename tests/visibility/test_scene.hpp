#pragma once
// Helpers the visibility tests share: a scene of box occluders with its BSP, boxes by
// centre and half-size, and the invariant of both occlusion buffers' z-pyramids.

#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/convex_polyhedron.hpp"
#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace dsoc::visibility::testing {

/// Box occluders; build() once they are all added. Or a test world's occluders, with
/// the BSP built.
struct Scene {
    Scene() = default;
    explicit Scene(TestWorld tw) : world(std::move(tw.world)) { build(); }

    OccluderWorld world;
    BspTree bsp;
    void add_box(glm::vec3 lo, glm::vec3 hi) {
        (void)world.add(ConvexPolyhedron::from_aabb({lo, hi}));
    }
    void build() { bsp.build(world); }
};

/// The cube of half-size `h` around `c`.
inline Aabb cube(glm::vec3 c, float h) {
    return Aabb::from_center_half_extents(c, glm::vec3(h));
}

/// The box of half-extents `h` around `c`.
inline Aabb region_at(glm::vec3 c, glm::vec3 h) {
    return Aabb::from_center_half_extents(c, h);
}

/// Expects every texel of levels 1.. of `buffer` (an OcclusionBuffer or a
/// RegionOcclusionBuffer of `face_resolution`) to hold the max of its four children;
/// returns how many of them are finite.
template <class Buffer>
int expect_max_pyramid(const Buffer& buffer, int face_resolution) {
    int finite = 0;
    for (int face = 0; face < 6; ++face) {
        for (int level = 1; level < buffer.levels(); ++level) {
            const int size = face_resolution >> level;
            for (int y = 0; y < size; ++y) {
                for (int x = 0; x < size; ++x) {
                    const float expected =
                        std::max(std::max(buffer.depth(face, level - 1, 2 * x, 2 * y),
                                          buffer.depth(face, level - 1, 2 * x + 1, 2 * y)),
                                 std::max(buffer.depth(face, level - 1, 2 * x, 2 * y + 1),
                                          buffer.depth(face, level - 1, 2 * x + 1, 2 * y + 1)));
                    EXPECT_EQ(buffer.depth(face, level, x, y), expected);
                    finite += expected < 1e30f ? 1 : 0;
                }
            }
        }
    }
    return finite;
}

/// Builds a `Buffer` (OcclusionBuffer or RegionOcclusionBuffer) of face resolution 32
/// from `from` (its eye or region) over a 5 x 5 corridor world, and expects written
/// texels and a pyramid of 6 levels (32 .. 1) each holding the max of its children.
template <class Buffer, class Config, class From>
void expect_pyramid_of_maxima(const From& from) {
    const Scene s(make_corridor_world(5, 5, 5));
    Config config;
    config.face_resolution = 32;
    Buffer buffer(config);
    buffer.build(from, s.world, s.bsp);
    ASSERT_GT(buffer.stats().texels_written, 0);
    EXPECT_GT(expect_max_pyramid(buffer, config.face_resolution), 0);
    EXPECT_EQ(buffer.levels(), 6);
}

/// Half-sizes of the property tests' random boxes: a fifth `tiny`, seven tenths
/// mid + mid_span * u, the rest large + large_span * u (u uniform in [0, 1)).
struct BoxSizes {
    float tiny, mid, mid_span, large, large_span;
};

/// The dice of a randomized test over a test world: a seeded generator, uniform draws
/// in [0, 1) and uniform points of the world's play area, drawn in the order of the
/// calls (the same run for a seed).
class WorldDice {
public:
    WorldDice(const Aabb& area, std::uint32_t seed) : rng(seed), area_(area) {}

    /// Uniform in [0, 1).
    float unit() { return unit_(rng); }
    /// Uniform in the play area.
    glm::vec3 point() { return area_.min + area_.size() * glm::vec3(unit(), unit(), unit()); }

    std::mt19937 rng; ///< for whole-number draws: rng() % n

private:
    Aabb area_;
    std::uniform_real_distribution<float> unit_{0.0f, 1.0f};
};

/// The property tests' random box number `b`: odd ones around a random vertex of a
/// random occluder of `world`, the others around a point of the play area; each axis of
/// the half-size scaled by 0.5..1.5. Draws from `dice` in a fixed order (the same boxes
/// for a seed).
inline Aabb random_test_box(WorldDice& dice, const OccluderWorld& world, int b,
                            const BoxSizes& sizes) {
    const float size_pick = dice.unit();
    const float h = size_pick < 0.2f
                        ? sizes.tiny
                        : (size_pick < 0.9f ? sizes.mid + sizes.mid_span * dice.unit()
                                            : sizes.large + sizes.large_span * dice.unit());
    glm::vec3 c = dice.point();
    if (b % 2 == 1) {
        const auto& near = world.occluder(static_cast<OccluderId>(dice.rng() % world.size()));
        c = near.vertices()[dice.rng() % near.vertices().size()] +
            glm::vec3(dice.unit() - 0.5f, dice.unit() - 0.5f, dice.unit() - 0.5f) * 40.0f;
    }
    const glm::vec3 half(h * (0.5f + dice.unit()), h * (0.5f + dice.unit()),
                         h * (0.5f + dice.unit()));
    return Aabb::from_center_half_extents(c, half);
}

/// Expects `problems`, what a config's validate() returned, to be one per field of
/// `fields`, in that order, each naming its field.
inline void expect_problems_naming(const std::vector<std::string>& problems,
                                   std::initializer_list<const char*> fields) {
    ASSERT_EQ(problems.size(), fields.size());
    std::size_t i = 0;
    for (const char* field : fields) {
        EXPECT_NE(problems[i].find(field), std::string::npos) << problems[i];
        ++i;
    }
}

/// "(x, y, z)", for failure messages.
inline std::string text(glm::vec3 p) {
    std::ostringstream out;
    out << "(" << p.x << ", " << p.y << ", " << p.z << ")";
    return out.str();
}

/// "(min)-(max)", for failure messages.
inline std::string text(const Aabb& box) {
    return text(box.min) + "-" + text(box.max);
}

} // namespace dsoc::visibility::testing
