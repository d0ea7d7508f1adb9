// The Embree oracle against the exact brute-force segment test of dsoc::visibility:
// two independent implementations of "does an occluder's interior cross this segment".

#include "dsoc/eval/ray_oracle.hpp"
#include "dsoc/visibility/occluder_world.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <random>

namespace dsoc::eval {
namespace {

glm::vec3 random_point(std::mt19937& rng, const visibility::Aabb& b) {
    std::uniform_real_distribution<float> x(b.min.x, b.max.x);
    std::uniform_real_distribution<float> y(b.min.y, b.max.y);
    std::uniform_real_distribution<float> z(b.min.z, b.max.z);
    return {x(rng), y(rng), z(rng)};
}

/// The rooms map, its occluders as a world, the exact reference over them and the
/// Embree oracle: the two implementations the tests compare.
struct Rooms {
    std::shared_ptr<const maps::Map> map = testing::rooms_map();
    visibility::OccluderWorld world = world_of(*map);
    visibility::ReferenceVisibility reference{world};
    RayOracle oracle{map->occluders};

    static visibility::OccluderWorld world_of(const maps::Map& m) {
        visibility::OccluderWorld w;
        for (const auto& o : m.occluders) {
            w.add(o);
        }
        return w;
    }
};

/// True when `p` is strictly inside some occluder. A segment between two points
/// inside the same solid crosses no face: a surface ray caster cannot see it, the
/// reference calls it blocked. The evaluation never asks that (eyes and entity boxes
/// are in free space), so the comparison keeps to free-space endpoints.
bool inside_any(const visibility::OccluderWorld& world, glm::vec3 p) {
    for (visibility::OccluderId id = 0; id < world.size(); ++id) {
        bool inside = true;
        for (const auto& plane : world.solid_planes(id)) {
            inside = inside && plane.signed_distance(p) < 0.0f;
        }
        if (inside) {
            return true;
        }
    }
    return false;
}

TEST(RayOracle, AgreesWithReferenceOnRandomSegments) {
    const Rooms rooms;
    const auto& map = rooms.map;
    const auto& world = rooms.world;
    const auto& reference = rooms.reference;
    const auto& oracle = rooms.oracle;
    ASSERT_GT(oracle.triangle_count(), 0u);

    std::mt19937 rng(12345);
    // Segments between random points, and between points at eye height (mostly in the
    // free space of the rooms, where the answers are interesting).
    visibility::Aabb eye_level = map->bounds;
    eye_level.min.z = 20.0f;
    eye_level.max.z = 80.0f;
    int blocked = 0;
    int disagreements = 0;
    constexpr int kSegments = 20000;
    for (int i = 0; i < kSegments; ++i) {
        const auto& space = i % 2 == 0 ? map->bounds : eye_level;
        const glm::vec3 a = random_point(rng, space);
        // Every other segment short (within a room or two), so that free ones abound.
        const glm::vec3 b =
            i % 4 < 2 ? random_point(rng, space)
                      : glm::clamp(a + random_point(rng, {glm::vec3(-400.0f), glm::vec3(400.0f)}),
                                   space.min, space.max);
        if (inside_any(world, a) || inside_any(world, b)) {
            --i;
            continue;
        }
        const bool expected = reference.segment_blocked(a, b);
        const bool got = oracle.segment_blocked(a, b);
        blocked += expected ? 1 : 0;
        if (expected != got) {
            ++disagreements;
            ADD_FAILURE() << "segment (" << a.x << "," << a.y << "," << a.z << ") -> (" << b.x
                          << "," << b.y << "," << b.z << "): reference "
                          << (expected ? "blocked" : "free") << ", oracle "
                          << (got ? "blocked" : "free");
            if (disagreements > 10) {
                break;
            }
        }
    }
    // Both kinds must be well represented for the comparison to mean anything.
    EXPECT_GT(blocked, kSegments / 10);
    EXPECT_GT(kSegments - blocked, kSegments / 10);
}

TEST(RayOracle, TouchingAFaceIsNotBlocking) {
    const auto box = visibility::ConvexPolyhedron::from_aabb({{0, 0, 0}, {10, 10, 10}});
    const RayOracle oracle(std::span(&box, 1));
    EXPECT_TRUE(oracle.segment_blocked({-5, 5, 5}, {15, 5, 5}));
    EXPECT_FALSE(oracle.segment_blocked({-5, 5, 5}, {0, 5, 5}));    // ends on the face
    EXPECT_FALSE(oracle.segment_blocked({-5, 20, 5}, {15, 20, 5})); // misses
}

TEST(RayOracle, FrontSamplesCoverTheFacesTurnedToTheEye) {
    const visibility::Aabb box{{0, 0, 0}, {10, 10, 10}};
    std::vector<glm::vec3> s;
    RayOracle::front_samples({-5, 5, 5}, box, 5, s); // one face: x = 0
    EXPECT_EQ(s.size(), 1u + 25u);
    s.clear();
    RayOracle::front_samples({-5, -5, 5}, box, 5, s); // two faces sharing an edge
    EXPECT_EQ(s.size(), 1u + 25u + 20u);
    s.clear();
    RayOracle::front_samples({-5, -5, -5}, box, 5, s); // three faces sharing a corner
    EXPECT_EQ(s.size(), 1u + 25u + 20u + 16u);
    for (const auto& p : s) {
        EXPECT_TRUE(box.contains(p));
    }
}

TEST(RayOracle, BoxAnswersAgreeWithReference) {
    // The reference samples all six faces, the oracle the faces turned toward the eye:
    // different samples, so allow a few disagreements, but every oracle "visible" is a
    // real unblocked segment and the two must agree almost always.
    const Rooms rooms;
    const auto& map = rooms.map;
    const auto& world = rooms.world;
    const auto& reference = rooms.reference;
    const auto& oracle = rooms.oracle;
    std::mt19937 rng(7);
    visibility::Aabb space = map->bounds;
    space.min.z = 30.0f;
    space.max.z = 60.0f;
    int visible = 0;
    int disagreements = 0;
    constexpr int kPairs = 3000;
    for (int i = 0; i < kPairs; ++i) {
        const glm::vec3 eye = random_point(rng, space);
        const glm::vec3 c = random_point(rng, space);
        if (inside_any(world, eye) || inside_any(world, c)) {
            --i;
            continue;
        }
        const visibility::Aabb box{c - glm::vec3(15, 15, 28), c + glm::vec3(15, 15, 28)};
        const bool ref = reference.test_box(eye, box, 5) == visibility::Visibility::visible;
        const bool got = oracle.box_visible(eye, box, 5);
        visible += ref ? 1 : 0;
        disagreements += ref != got ? 1 : 0;
    }
    EXPECT_GT(visible, kPairs / 100);
    EXPECT_LE(disagreements, kPairs / 100) << disagreements << " of " << kPairs;
}

} // namespace
} // namespace dsoc::eval
