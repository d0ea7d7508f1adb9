// The Embree oracle against the exact brute-force segment test of dsoc::visibility:
// two independent implementations of "does an occluder's interior cross this segment".

#include "dsoc/eval/ray_oracle.hpp"
#include "dsoc/maps/curved_surface.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/visibility/occluder_world.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "support/openarena.hpp"
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

// A long ray that rises into a point just above a block's top edge crosses the block's
// corner about half a unit before its end. The crossing blocks (the reference agrees);
// a trim in proportion to the length (1e-3 of 2,236 units) once dropped it, and so
// "saw" entities standing right behind walls from far away (pul1ctf: a player 0.9
// units behind a wall's corner, seen from 1,175 units).
TEST(RayOracle, ACornerCrossedNearTheEndOfALongRayBlocks) {
    const auto block = visibility::ConvexPolyhedron::from_aabb({{0, 0, 0}, {10, 10, 10}});
    const RayOracle oracle(std::span(&block, 1));
    const glm::vec3 point{0.5f, 5.0f, 10.2f};
    const glm::vec3 eye = point - 2000.5f * glm::vec3{1.0f, 0.0f, 0.5f};
    ASSERT_TRUE(visibility::segment_blocked_by(eye, point, block.planes()));
    EXPECT_TRUE(oracle.segment_blocked(eye, point));
    const glm::vec3 points[] = {point};
    EXPECT_FALSE(oracle.any_visible(eye, points)); // the 16-ray path trims alike
    // Just above the corner's reach the same ray is clear.
    const glm::vec3 higher = point + glm::vec3{0.0f, 0.0f, 0.3f};
    ASSERT_FALSE(
        visibility::segment_blocked_by(eye + glm::vec3{0.0f, 0.0f, 0.3f}, higher, block.planes()));
    EXPECT_FALSE(oracle.segment_blocked(eye + glm::vec3{0.0f, 0.0f, 0.3f}, higher));
}

TEST(RayOracle, SurfaceTrianglesBlockToo) {
    const auto far_block =
        visibility::ConvexPolyhedron::from_aabb({{100, 100, 100}, {110, 110, 110}});
    const glm::vec3 triangle[] = {{5, -10, -10}, {5, 10, -10}, {5, 0, 10}};
    const RayOracle with(std::span(&far_block, 1), triangle);
    const RayOracle without(std::span(&far_block, 1));
    EXPECT_EQ(with.triangle_count(), without.triangle_count() + 1);
    EXPECT_TRUE(with.segment_blocked({0, 0, 0}, {10, 0, 0}));
    EXPECT_FALSE(without.segment_blocked({0, 0, 0}, {10, 0, 0}));
    EXPECT_FALSE(with.segment_blocked({0, 20, 0}, {10, 20, 0})); // beside it
    const glm::vec3 points[] = {{10, 0, 0}, {10, 0, 1}};
    EXPECT_FALSE(with.any_visible({0, 0, 0}, points));
    EXPECT_TRUE(without.any_visible({0, 0, 0}, points));
}

// pul1ctf draws its round walls as curved patches with a caulk brush behind each: the
// compiler's vis stops at the caulk, the occluders hold neither. An eye and a player
// box where the occluders alone leave a clear line, through patches the game draws
// opaque, and the compiler's PVS (rightly) hides the box: the oracle with the patches
// agrees with the PVS.
TEST(RayOracle, Pul1ctfsPatchesBlockWhatTheCompilersVisHides) {
    DSOC_REQUIRE_OPENARENA();
    const auto map = maps::load_map("pul1ctf", maps::MapSearch::from_environment());
    ASSERT_TRUE(map.ok()) << map.error().message();
    ASSERT_GT(map->opaque_patches.size(), 100u);
    std::vector<glm::vec3> triangles;
    for (const maps::CurvedSurface& patch : map->opaque_patches) {
        maps::tessellate(patch, 16, triangles);
    }
    const RayOracle occluders_only(map->occluders);
    const RayOracle with_patches(map->occluders, triangles);
    const glm::vec3 eye{262.44833f, -895.3668f, 404.7917f};
    const visibility::Aabb box{{-530.6101f, 1466.7593f, 0.13233376f},
                               {-500.6101f, 1496.7593f, 56.13233f}};
    EXPECT_TRUE(occluders_only.box_visible(eye, box, 5));
    EXPECT_FALSE(with_patches.box_visible(eye, box, 5));
    ASSERT_NE(map->pvs, nullptr);
    std::vector<std::int32_t> eye_clusters;
    ASSERT_TRUE(map->pvs->clusters_of({eye, eye}, eye_clusters));
    std::vector<std::uint8_t> row;
    map->pvs->union_of_rows(eye_clusters, row);
    std::vector<std::int32_t> scratch;
    EXPECT_FALSE(map->pvs->may_see(row, box, scratch));
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
