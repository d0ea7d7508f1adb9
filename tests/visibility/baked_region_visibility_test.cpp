// The baked table as a culler stage: what it proves holds against brute-force rays,
// what it does not cover goes to the next stage (never culled by guess), and prepared
// boxes, their runs of cells and merged TBV keys answer as the plain boxes do.

#include "dsoc/visibility/baked_region_visibility.hpp"
#include "dsoc/visibility/cell_bake.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/test_worlds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace dsoc::visibility {
namespace {

/// A next stage that answers `answer` and counts the calls that reach it.
class CountingStage final : public RegionVisibility {
public:
    explicit CountingStage(Visibility answer, int* calls) : answer_(answer), calls_(calls) {}
    void build(const Aabb& /*region*/) override {}
    [[nodiscard]] Visibility test_box(const Aabb& /*box*/) const override {
        ++*calls_;
        return answer_;
    }

private:
    Visibility answer_;
    int* calls_;
};

struct Baked {
    std::shared_ptr<const OccluderScene> scene;
    Aabb play_area;
    std::shared_ptr<const CellVisibilityTable> table;
};

const Baked& corridor_table() {
    static const Baked baked = [] {
        const TestWorld w = make_corridor_world(7, 2, 2);
        Baked b;
        b.scene = OccluderScene::build(w.world.occluders());
        b.play_area = w.play_area;
        CellBakeConfig config;
        config.cell_size = 48.0f;
        config.threads = 2;
        const auto grid = CellGrid::covering(w.world.bounds(), config.cell_size);
        b.table = std::make_shared<const CellVisibilityTable>(
            bake_cell_visibility(*b.scene, grid, config));
        return b;
    }();
    return baked;
}

Aabb random_box(std::mt19937& rng, const Aabb& area, float min_size, float max_size) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const glm::vec3 size =
        glm::vec3(min_size) + glm::vec3(unit(rng), unit(rng), unit(rng)) * (max_size - min_size);
    const glm::vec3 lo =
        area.min + glm::vec3(unit(rng), unit(rng), unit(rng)) * (area.size() - size);
    return {lo, lo + size};
}

TEST(BakedRegionVisibility, WhatItHidesNoSegmentReachesAndItHidesMuch) {
    const Baked& b = corridor_table();
    const ReferenceVisibility reference(b.scene->world);
    BakedRegionVisibility stage(b.table, nullptr);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    int tests = 0;
    int hidden = 0;
    int clear = 0;
    for (int r = 0; r < 60; ++r) {
        const Aabb region = random_box(rng, b.play_area, 16.0f, 120.0f);
        stage.build(region);
        for (int k = 0; k < 40; ++k) {
            const Aabb box = random_box(rng, b.play_area, 16.0f, 64.0f);
            ++tests;
            if (stage.test_box(box) != Visibility::occluded) {
                continue;
            }
            ++hidden;
            for (int s = 0; s < 64; ++s) {
                const glm::vec3 p =
                    region.min + glm::vec3(unit(rng), unit(rng), unit(rng)) * region.size();
                const glm::vec3 q =
                    box.min + glm::vec3(unit(rng), unit(rng), unit(rng)) * box.size();
                clear += reference.segment_blocked(p, q) ? 0 : 1;
            }
        }
    }
    EXPECT_EQ(clear, 0) << "clear segments into boxes the table called hidden";
    EXPECT_GT(hidden, tests / 5) << hidden << " of " << tests << " hidden";
}

TEST(BakedRegionVisibility, WhatTheTableDoesNotCoverGoesToTheNextStage) {
    const Baked& b = corridor_table();
    const Aabb grid_box = b.table->grid().bounds();
    int calls = 0;
    BakedRegionVisibility stage(b.table,
                                std::make_unique<CountingStage>(Visibility::occluded, &calls));
    // A region half outside the grid: the table says nothing, every box goes on.
    const Aabb outside{grid_box.min - glm::vec3(40.0f), grid_box.min + glm::vec3(40.0f)};
    stage.build(outside);
    EXPECT_FALSE(stage.active());
    const Aabb far_box =
        Aabb::from_center_half_extents(grid_box.max - glm::vec3(100.0f), glm::vec3(16.0f));
    EXPECT_EQ(stage.test_box(far_box), Visibility::occluded); // the next stage's answer
    EXPECT_EQ(calls, 1);
    // Without a next stage, an uncovered region is "visible" for every box.
    BakedRegionVisibility alone(b.table, nullptr);
    alone.build(outside);
    EXPECT_EQ(alone.test_box(far_box), Visibility::visible);
    PreparedBox p;
    alone.prepare(far_box, p);
    EXPECT_EQ(alone.test_prepared_coarse(p), Visibility::visible);
    // A covered region and a box half outside the grid: the box goes on.
    const Aabb inside = Aabb::from_center_half_extents(b.play_area.center(), glm::vec3(30.0f));
    stage.build(inside);
    EXPECT_TRUE(stage.active());
    calls = 0;
    const Aabb straddling{grid_box.max - glm::vec3(20.0f), grid_box.max + glm::vec3(20.0f)};
    EXPECT_EQ(stage.test_box(straddling), Visibility::occluded);
    EXPECT_EQ(calls, 1);
    alone.build(inside);
    EXPECT_EQ(alone.test_box(straddling), Visibility::visible);
}

TEST(BakedRegionVisibility, PreparedWordsAnswerAsCellsAndMergedKeysHideOnlyTogether) {
    const Baked& b = corridor_table();
    const CellVisibilityTable& t = *b.table;
    BakedRegionVisibility stage(b.table, nullptr);
    std::mt19937 rng(11);
    int merged_checks = 0;
    for (int r = 0; r < 40; ++r) {
        const Aabb region = random_box(rng, b.play_area, 16.0f, 100.0f);
        stage.build(region);
        std::vector<PreparedBox> boxes(12);
        for (auto& p : boxes) {
            const Aabb box = random_box(rng, b.play_area, 16.0f, 200.0f);
            stage.prepare(box, p);
            // The keys hold exactly the open cells of the box (cell by cell here).
            std::vector<OpenCell> cells;
            glm::ivec3 lo;
            glm::ivec3 hi;
            const bool in_grid = t.grid().range_of(box, lo, hi);
            for (int z = lo.z; in_grid && z <= hi.z; ++z) {
                for (int y = lo.y; y <= hi.y; ++y) {
                    for (int x = lo.x; x <= hi.x; ++x) {
                        const OpenCell c = t.open_index(t.grid().index({x, y, z}));
                        if (c != kSolidCell) {
                            cells.push_back(c);
                        }
                    }
                }
            }
            ASSERT_EQ(in_grid && !cells.empty(), p.prepared);
            std::vector<OpenCell> from_words; // triples (word, low bits, high bits)
            for (std::size_t k = 0; k + 2 < p.keys.size(); k += 3) {
                ASSERT_TRUE(k == 0 || p.keys[k - 3] < p.keys[k]) << "words must increase";
                const std::uint64_t mask = static_cast<std::uint32_t>(p.keys[k + 1]) |
                                           std::uint64_t{static_cast<std::uint32_t>(p.keys[k + 2])}
                                               << 32;
                ASSERT_NE(mask, 0u);
                for (int bit = 0; bit < 64; ++bit) {
                    if ((mask >> bit & 1u) != 0) {
                        from_words.push_back(static_cast<OpenCell>(p.keys[k] * 64 + bit));
                    }
                }
            }
            std::sort(cells.begin(), cells.end());
            ASSERT_EQ(cells, from_words);
            ASSERT_EQ(stage.test_prepared(p), stage.test_box(box));
        }
        for (std::size_t i = 0; i + 1 < boxes.size(); i += 2) {
            if (!boxes[i].prepared || !boxes[i + 1].prepared) {
                continue;
            }
            PreparedBox merged = boxes[i];
            stage.merge_prepared(merged, boxes[i + 1]);
            const bool both = stage.test_prepared_coarse(boxes[i]) == Visibility::occluded &&
                              stage.test_prepared_coarse(boxes[i + 1]) == Visibility::occluded;
            EXPECT_EQ(stage.test_prepared_coarse(merged) == Visibility::occluded, both);
            ++merged_checks;
        }
    }
    EXPECT_GT(merged_checks, 100);
}

TEST(BakedRegionVisibility, AWalkingRegionAnswersAsAFreshBuildOfEachRegion) {
    // The union is rebuilt from the slabs the last region left (slabs per x): a region
    // that wanders by small steps, often along x only, must answer every box exactly
    // as a culler built for that region alone.
    const Baked& b = corridor_table();
    BakedRegionVisibility walking(b.table, nullptr);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> step(-40.0f, 40.0f);
    std::bernoulli_distribution along_x(0.6);
    Aabb region = random_box(rng, b.play_area, 60.0f, 120.0f);
    int hidden = 0;
    int tests = 0;
    for (int r = 0; r < 400; ++r) {
        glm::vec3 move{step(rng), along_x(rng) ? 0.0f : step(rng), 0.0f};
        if (r % 50 == 49) {
            move.z = step(rng);
        }
        const Aabb moved{region.min + move, region.max + move};
        if (b.play_area.contains(moved)) {
            region = moved;
        }
        walking.build(region);
        BakedRegionVisibility fresh(b.table, nullptr);
        fresh.build(region);
        ASSERT_EQ(walking.active(), fresh.active()) << r;
        for (int k = 0; k < 30; ++k) {
            const Aabb box = random_box(rng, b.play_area, 16.0f, 64.0f);
            const Visibility expected = fresh.test_box(box);
            ASSERT_EQ(walking.test_box(box), expected) << "region " << r << " box " << k;
            ++tests;
            hidden += expected == Visibility::occluded ? 1 : 0;
        }
    }
    EXPECT_GT(hidden, tests / 10); // something is culled
}

TEST(BakedRegionVisibility, AFactoryWithoutATableIsTheNextStage) {
    int calls = 0;
    const auto factory = with_baked_stage(
        nullptr, [&calls] { return std::make_unique<CountingStage>(Visibility::visible, &calls); });
    const auto culler = factory();
    EXPECT_EQ(dynamic_cast<BakedRegionVisibility*>(culler.get()), nullptr);
}

} // namespace
} // namespace dsoc::visibility
