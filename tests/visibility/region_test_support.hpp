#pragma once
// Helpers shared by the from-region culling tests (shaft, fusion, portals): a
// brute-force certificate of visibility from a region, and a world whose walls are
// built from many brushes.

#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include <random>

namespace dsoc::visibility::testing {

inline OccluderId add_box(OccluderWorld& world, glm::vec3 lo, glm::vec3 hi) {
    return world.add(ConvexPolyhedron::from_aabb({lo, hi}));
}

/// True when some eye of an n x n x n lattice over `region` (corners included) sees
/// `box` (5 x 5 samples per face): a certificate that the box is visible from the
/// region. False is evidence, not proof, that it is hidden.
inline bool seen_from_lattice(const ReferenceVisibility& ref, const Aabb& region, const Aabb& box,
                              int n = 5) {
    const float step = 1.0f / static_cast<float>(n - 1);
    for (int k = 0; k < n * n * n; ++k) {
        const glm::vec3 f(static_cast<float>(k % n), static_cast<float>((k / n) % n),
                          static_cast<float>(k / (n * n)));
        if (ref.test_box(region.min + region.size() * f * step, box, 5) == Visibility::visible) {
            return true;
        }
    }
    return false;
}

/// The corridor world with every box brush cut into 2-4 pieces along its longest axis,
/// some pieces thickened on one side: the same kind of walls a level designer builds
/// from many brushes, which single-occluder tests cannot fuse.
inline TestWorld fragmented_corridor_world(std::uint32_t seed) {
    const TestWorld base = make_corridor_world(seed, 4, 4);
    std::mt19937 rng(seed);
    TestWorld out;
    out.play_area = base.play_area;
    for (OccluderId id = 0; id < base.world.size(); ++id) {
        const ConvexPolyhedron& o = base.world.occluder(id);
        if (o.planes().size() != 6 || base.world.face_planes(id).size() != 6 ||
            o.vertices().size() != 8) {
            out.world.add(o);
            continue;
        }
        const Aabb b = o.bounds();
        const glm::vec3 s = b.size();
        const int axis = s.x >= s.y && s.x >= s.z ? 0 : (s.y >= s.z ? 1 : 2);
        const int thin = s.x <= s.y && s.x <= s.z ? 0 : (s.y <= s.z ? 1 : 2);
        const int pieces = 2 + static_cast<int>(rng() % 3);
        for (int p = 0; p < pieces; ++p) {
            Aabb piece = b;
            piece.min[axis] = b.min[axis] + s[axis] * static_cast<float>(p) / pieces;
            piece.max[axis] = b.min[axis] + s[axis] * static_cast<float>(p + 1) / pieces;
            if (thin != axis && rng() % 2 == 0) {
                (rng() % 2 == 0 ? piece.min[thin] : piece.max[thin]) +=
                    (rng() % 2 == 0 ? -1.0f : 1.0f) * 4.0f;
                if (piece.min[thin] >= piece.max[thin]) {
                    piece = b; // never thinner than nothing
                    piece.min[axis] = b.min[axis] + s[axis] * static_cast<float>(p) / pieces;
                    piece.max[axis] = b.min[axis] + s[axis] * static_cast<float>(p + 1) / pieces;
                }
            }
            add_box(out.world, piece.min, piece.max);
        }
    }
    return out;
}

/// Calls `visit(region, box)` `count` times with random pairs in `tw.play_area`: an eye
/// region of half extents up to 60 x 60 x 30 units and a player-sized box (30 x 30 x
/// 56), the pairs the random property tests of the region cullers judge.
template <class Visit>
void for_random_region_box_pairs(const TestWorld& tw, std::mt19937& rng, int count, Visit&& visit) {
    std::uniform_real_distribution<float> ux(tw.play_area.min.x, tw.play_area.max.x);
    std::uniform_real_distribution<float> uy(tw.play_area.min.y, tw.play_area.max.y);
    std::uniform_real_distribution<float> uz(tw.play_area.min.z, tw.play_area.max.z);
    std::uniform_real_distribution<float> half(0.0f, 60.0f);
    for (int i = 0; i < count; ++i) {
        const glm::vec3 c(ux(rng), uy(rng), uz(rng));
        const Aabb region{c - glm::vec3(half(rng), half(rng), half(rng) * 0.5f),
                          c + glm::vec3(half(rng), half(rng), half(rng) * 0.5f)};
        const glm::vec3 b(ux(rng), uy(rng), uz(rng));
        const Aabb box{b - glm::vec3(15, 15, 28), b + glm::vec3(15, 15, 28)};
        visit(region, box);
    }
}

/// Moves `region` and `box` each by a random step of up to `reach` units along x and
/// y: a pair of the hint tests, moving as a viewer and an entity do between ticks.
inline void step_pair(std::mt19937& rng, float reach, Aabb& region, Aabb& box) {
    std::uniform_real_distribution<float> step(-reach, reach);
    const float rx = step(rng);
    const float ry = step(rng);
    const float bx = step(rng);
    const float by = step(rng);
    region = Aabb{region.min + glm::vec3(rx, ry, 0.0f), region.max + glm::vec3(rx, ry, 0.0f)};
    box = Aabb{box.min + glm::vec3(bx, by, 0.0f), box.max + glm::vec3(bx, by, 0.0f)};
}

} // namespace dsoc::visibility::testing
