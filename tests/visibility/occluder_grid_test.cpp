// The occluder grid against brute force: whatever its cell size (and after it coarsens
// itself to bound its lists), a box query finds exactly the occluders whose bounds
// overlap the box.

#include "dsoc/visibility/occluder_grid.hpp"
#include "region_test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace dsoc::visibility {
namespace {

using testing::add_box;

std::vector<OccluderId> brute_force(const OccluderWorld& world, const Aabb& box) {
    std::vector<OccluderId> out;
    for (OccluderId id = 0; id < world.size(); ++id) {
        if (world.occluder(id).bounds().overlaps(box)) {
            out.push_back(id);
        }
    }
    return out;
}

std::vector<OccluderId> found(const OccluderGrid& grid, const Aabb& box) {
    OccluderGrid::Scratch scratch;
    grid.query(box, scratch);
    std::vector<OccluderId> out = scratch.found;
    std::sort(out.begin(), out.end());
    return out;
}

TEST(OccluderGrid, BoxQueriesFindWhatBruteForceFindsAtAnyCellSize) {
    std::mt19937 rng(128);
    std::uniform_real_distribution<float> at(-3000.0f, 3000.0f);
    std::uniform_real_distribution<float> size(4.0f, 600.0f);
    OccluderWorld world;
    for (int i = 0; i < 300; ++i) {
        const glm::vec3 lo{at(rng), at(rng), at(rng) * 0.2f};
        add_box(world, lo, lo + glm::vec3(size(rng), size(rng), size(rng) * 0.5f));
    }
    const OccluderGrid grids[] = {OccluderGrid(world, 16.0f), OccluderGrid(world),
                                  OccluderGrid(world, 1024.0f)};
    std::size_t hits = 0;
    for (int q = 0; q < 400; ++q) {
        const glm::vec3 lo{at(rng), at(rng), at(rng) * 0.2f};
        const Aabb box{lo, lo + glm::vec3(size(rng), size(rng), size(rng))};
        const std::vector<OccluderId> expected = brute_force(world, box);
        hits += expected.size();
        for (const OccluderGrid& grid : grids) {
            ASSERT_EQ(found(grid, box), expected)
                << "query " << q << ", cells of " << grid.cell_size();
        }
    }
    EXPECT_GT(hits, 100u); // the queries met occluders
}

TEST(OccluderGrid, CoarsensItselfWhereLargeBrushesWouldOverfillFineCells) {
    // 40 floors 16,000 units square: at 32-unit cells each would be listed in 500 x 500
    // cells (10M entries in all), past the bound.
    OccluderWorld world;
    for (int i = 0; i < 40; ++i) {
        const auto z = static_cast<float>(i) * 64.0f;
        add_box(world, {-8000, -8000, z}, {8000, 8000, z + 16});
    }
    const OccluderGrid grid(world, 32.0f);
    EXPECT_GT(grid.cell_size(), 32.0f);
    const Aabb box{{100, 100, 60}, {140, 140, 70}};
    EXPECT_EQ(found(grid, box), brute_force(world, box));
    EXPECT_EQ(OccluderGrid(world, 1024.0f).cell_size(), 1024.0f); // already coarse enough
}

} // namespace
} // namespace dsoc::visibility
