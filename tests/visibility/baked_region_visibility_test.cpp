// The baked table as a culler stage: what it proves holds against brute-force rays,
// what it does not cover goes to the next stage (never culled by guess), prepared
// boxes, their row words and merged TBV keys answer as the plain boxes do, and the
// InterestManager's bulk answers behind the table alone are its one-by-one answers.

#include "dsoc/visibility/baked_region_visibility.hpp"
#include "dsoc/visibility/cell_bake.hpp"
#include "dsoc/visibility/interest_manager.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
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

/// How many of 64 segments between random points of `region` and `box` no occluder
/// blocks (brute force).
int clear_segments(const ReferenceVisibility& reference, const Aabb& region, const Aabb& box,
                   std::mt19937& rng) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    int clear = 0;
    for (int s = 0; s < 64; ++s) {
        const glm::vec3 p = region.min + glm::vec3(unit(rng), unit(rng), unit(rng)) * region.size();
        const glm::vec3 q = box.min + glm::vec3(unit(rng), unit(rng), unit(rng)) * box.size();
        clear += reference.segment_blocked(p, q) ? 0 : 1;
    }
    return clear;
}

TEST(BakedRegionVisibility, WhatItHidesNoSegmentReachesAndItHidesMuch) {
    const Baked& b = corridor_table();
    const ReferenceVisibility reference(b.scene->world);
    BakedRegionVisibility stage(b.table, nullptr);
    std::mt19937 rng(5);
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
            clear += clear_segments(reference, region, box, rng);
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

/// Whether `box` touches a cell of `table` that is uncovered (brute force over its cells).
bool touches_uncovered(const CellVisibilityTable& table, const Aabb& box) {
    glm::ivec3 lo;
    glm::ivec3 hi;
    if (!table.grid().range_of(box, lo, hi)) {
        return false;
    }
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            for (int x = lo.x; x <= hi.x; ++x) {
                if (table.open_index(table.grid().index({x, y, z})) == kUncoveredCell) {
                    return true;
                }
            }
        }
    }
    return false;
}

TEST(BakedRegionVisibility, UncoveredCellsAreNeverAnsweredAndChangeNoOtherAnswer) {
    // The corridor baked twice without the hierarchy (pair by pair, the slow twin):
    // once over every open cell, once with the upper half of the layers uncovered.
    const TestWorld w = make_corridor_world(7, 2, 2);
    const auto scene = OccluderScene::build(w.world.occluders());
    CellBakeConfig config;
    config.cell_size = 64.0f;
    config.threads = 2;
    config.top_level = 0;
    const auto grid = CellGrid::covering(w.world.bounds(), config.cell_size);
    ASSERT_GE(grid.dims.z, 2);
    std::vector<std::uint8_t> covered(grid.cell_count(), 0);
    for (std::uint32_t i = 0; i < grid.cell_count(); ++i) {
        covered[i] = grid.coords(i).z < grid.dims.z / 2 ? 1 : 0;
    }
    const CellVisibilityTable whole = bake_cell_visibility(*scene, grid, config);
    CellBakeStats stats;
    const auto part = std::make_shared<const CellVisibilityTable>(
        bake_cell_visibility(*scene, grid, config, nullptr, &stats, {}, covered));
    ASSERT_GT(part->uncovered_cells().size(), 0u);
    ASSERT_GT(part->open_count(), 0u);
    EXPECT_EQ(stats.uncovered_cells, part->uncovered_cells().size());
    EXPECT_EQ(part->open_count() + part->uncovered_cells().size(), whole.open_count());
    // Among the cells left, the same answers as the whole table.
    for (std::size_t a = 0; a < part->open_count(); ++a) {
        const OpenCell wa = whole.open_index(part->open_cells()[a]);
        for (std::size_t b = 0; b < part->open_count(); ++b) {
            const OpenCell wb = whole.open_index(part->open_cells()[b]);
            ASSERT_EQ(part->may_see(static_cast<OpenCell>(a), static_cast<OpenCell>(b)),
                      whole.may_see(wa, wb));
        }
    }
    EXPECT_GT(part->hidden_pairs(), 0u); // something is still culled
    // A region or a box touching an uncovered cell goes to the next stage, always.
    int calls = 0;
    BakedRegionVisibility stage(part,
                                std::make_unique<CountingStage>(Visibility::occluded, &calls));
    BakedRegionVisibility alone(part, nullptr);
    // The same stage with block unions: the same answers, the same calls.
    int block_calls = 0;
    BakedRegionVisibility stage_blocks(
        part, std::make_unique<CountingStage>(Visibility::occluded, &block_calls),
        BakedRegionVisibility::NextFor::after_table,
        std::make_shared<const CellBlockUnions>(*part));
    int from_blocks = 0;
    std::mt19937 rng(11);
    int hidden_by_table = 0;
    int uncovered_regions = 0;
    int uncovered_boxes = 0;
    for (int r = 0; r < 80; ++r) {
        const Aabb region = random_box(rng, w.play_area, 16.0f, 120.0f);
        stage.build(region);
        alone.build(region);
        stage_blocks.build(region);
        EXPECT_EQ(stage_blocks.active(), stage.active());
        EXPECT_EQ(stage_blocks.partial(), stage.partial());
        glm::ivec3 lo;
        glm::ivec3 hi;
        from_blocks += grid.range_of(region, lo, hi) && CellBlockUnions::covers(lo, hi) ? 1 : 0;
        const bool region_out = touches_uncovered(*part, region);
        uncovered_regions += region_out ? 1 : 0;
        if (region_out) {
            EXPECT_FALSE(stage.active());
        }
        for (int k = 0; k < 30; ++k) {
            const Aabb box = random_box(rng, w.play_area, 16.0f, 64.0f);
            const bool box_out = touches_uncovered(*part, box);
            uncovered_boxes += box_out ? 1 : 0;
            calls = 0;
            const Visibility v = stage.test_box(box);
            block_calls = 0;
            EXPECT_EQ(stage_blocks.test_box(box), v);
            EXPECT_EQ(block_calls, calls);
            PreparedBox p;
            alone.prepare(box, p);
            if (region_out || box_out) {
                EXPECT_EQ(calls, 1) << "the table answered for an uncovered cell";
                EXPECT_EQ(alone.test_prepared(p), Visibility::visible);
                EXPECT_EQ(alone.test_box(box), Visibility::visible);
            } else if (calls == 0) {
                EXPECT_EQ(v, Visibility::occluded);
                ++hidden_by_table;
            }
        }
    }
    EXPECT_GT(uncovered_regions, 5);
    EXPECT_GT(from_blocks, 10);
    EXPECT_GT(uncovered_boxes, 50);
    EXPECT_GT(hidden_by_table, 20);
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

/// A region that wanders and changes size by small steps along one axis or several,
/// built into one culler (with `blocks` or without), must answer every box exactly as a
/// culler built for that region alone from the table's rows.
void walk_a_region(std::shared_ptr<const CellBlockUnions> blocks) {
    const Baked& b = corridor_table();
    const CellGrid& grid = b.table->grid();
    BakedRegionVisibility walking(b.table, nullptr, BakedRegionVisibility::NextFor::after_table,
                                  blocks);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> step(-60.0f, 60.0f);
    std::bernoulli_distribution moves(0.45);
    std::uniform_int_distribution<int> how(0, 2); // both faces, only min, only max
    Aabb region = random_box(rng, b.play_area, 60.0f, 120.0f);
    int hidden = 0;
    int tests = 0;
    int x_alone = 0;     // steps whose cells changed in x alone: the slabs kept are reused
    int y_or_z = 0;      // steps whose cells changed in y or z: every slab is made again
    int from_blocks = 0; // ranges of two cells or more on every axis: built from blocks
    int from_rows = 0;   // the others: from the table's rows
    glm::ivec3 last_lo{0};
    glm::ivec3 last_hi{-1};
    for (int r = 0; r < 800; ++r) {
        Aabb moved = region;
        for (int axis = 0; axis < 3; ++axis) {
            if (!moves(rng)) {
                continue;
            }
            const float d = step(rng);
            const int faces = how(rng);
            moved.min[axis] += faces != 2 ? d : 0.0f;
            moved.max[axis] += faces != 1 ? d : 0.0f;
        }
        const glm::vec3 size = moved.size();
        if (b.play_area.contains(moved) && glm::all(glm::greaterThan(size, glm::vec3(16.0f))) &&
            glm::all(glm::lessThan(size, glm::vec3(520.0f)))) {
            region = moved;
        }
        walking.build(region);
        BakedRegionVisibility fresh(b.table, nullptr);
        fresh.build(region);
        ASSERT_EQ(walking.active(), fresh.active()) << r;
        ASSERT_EQ(walking.partial(), fresh.partial()) << r;
        glm::ivec3 lo;
        glm::ivec3 hi;
        if (grid.range_of(region, lo, hi)) {
            const bool same_yz =
                lo.y == last_lo.y && hi.y == last_hi.y && lo.z == last_lo.z && hi.z == last_hi.z;
            const bool same_x = lo.x == last_lo.x && hi.x == last_hi.x;
            x_alone += same_yz && !same_x ? 1 : 0;
            y_or_z += !same_yz ? 1 : 0;
            last_lo = lo;
            last_hi = hi;
            (CellBlockUnions::covers(lo, hi) ? from_blocks : from_rows) += 1;
        }
        for (int k = 0; k < 30; ++k) {
            const Aabb box = random_box(rng, b.play_area, 16.0f, 64.0f);
            const Visibility expected = fresh.test_box(box);
            ASSERT_EQ(walking.test_box(box), expected) << "region " << r << " box " << k;
            ++tests;
            hidden += expected == Visibility::occluded ? 1 : 0;
        }
    }
    EXPECT_GT(hidden, tests / 10); // something is culled
    EXPECT_GT(x_alone, 20);
    EXPECT_GT(y_or_z, 20);
    EXPECT_GT(from_blocks, 100); // both ways of building were exercised
    EXPECT_GT(from_rows, 20);
}

TEST(BakedRegionVisibility, AWalkingRegionAnswersAsAFreshBuildOfEachRegion) {
    // The union is rebuilt from the slabs the last region left (slabs per x).
    walk_a_region(nullptr);
}

TEST(BakedRegionVisibility, AWalkingRegionBuiltFromBlockUnionsAnswersAsTheRows) {
    // Ranges of two cells or more on every axis from the blocks, the others from the
    // slabs, one build after the other: a slab kept across block builds must still be
    // the slab of its x.
    walk_a_region(std::make_shared<const CellBlockUnions>(*corridor_table().table));
}

TEST(BakedRegionVisibility, AFactoryWithoutATableIsTheNextStage) {
    int calls = 0;
    const auto factory = with_baked_stage(
        nullptr, [&calls] { return std::make_unique<CountingStage>(Visibility::visible, &calls); });
    const auto culler = factory();
    EXPECT_EQ(dynamic_cast<BakedRegionVisibility*>(culler.get()), nullptr);
}

/// A BakedRegionVisibility that does not say its prepared tests are all its coarse
/// one, so that the InterestManager asks it entity by entity: the slow twin of the
/// manager's bulk path (test_entities_in_bulk()).
class OneByOne final : public RegionVisibility {
public:
    explicit OneByOne(
        std::shared_ptr<const CellVisibilityTable> table,
        std::unique_ptr<RegionVisibility> next = nullptr,
        BakedRegionVisibility::NextFor next_for = BakedRegionVisibility::NextFor::after_table)
        : stage_(std::move(table), std::move(next), next_for) {}
    void build(const Aabb& region) override { stage_.build(region); }
    [[nodiscard]] Visibility test_box(const Aabb& box) const override {
        return stage_.test_box(box);
    }
    [[nodiscard]] Visibility test_box_quick(const Aabb& box) const override {
        return stage_.test_box_quick(box);
    }
    [[nodiscard]] bool has_prepared_stage() const override { return stage_.has_prepared_stage(); }
    void prepare(const Aabb& box, PreparedBox& out) const override { stage_.prepare(box, out); }
    [[nodiscard]] Visibility test_prepared(const PreparedBox& p) const override {
        return stage_.test_prepared(p);
    }
    [[nodiscard]] Visibility test_prepared_quick(const PreparedBox& p) const override {
        return stage_.test_prepared_quick(p);
    }
    [[nodiscard]] Visibility test_box_hinted(const Aabb& box, std::uint32_t& hint) const override {
        return stage_.test_box_hinted(box, hint);
    }
    [[nodiscard]] Visibility test_prepared_hinted(const PreparedBox& p,
                                                  std::uint32_t& hint) const override {
        return stage_.test_prepared_hinted(p, hint);
    }
    void merge_prepared(PreparedBox& into, const PreparedBox& more) const override {
        stage_.merge_prepared(into, more);
    }
    [[nodiscard]] bool pair_shortcuts_pay() const override { return stage_.pair_shortcuts_pay(); }
    [[nodiscard]] Visibility test_prepared_coarse(const PreparedBox& p) const override {
        return stage_.test_prepared_coarse(p);
    }

private:
    BakedRegionVisibility stage_;
};

/// An exact culler that counts its builds and tests (of every instance it is given).
class CountingNext final : public RegionVisibility {
public:
    CountingNext(std::unique_ptr<RegionVisibility> inner, int* builds, int* tests)
        : inner_(std::move(inner)), builds_(builds), tests_(tests) {}
    void build(const Aabb& region) override {
        ++*builds_;
        inner_->build(region);
    }
    [[nodiscard]] Visibility test_box(const Aabb& box) const override {
        ++*tests_;
        return inner_->test_box(box);
    }
    [[nodiscard]] Visibility test_box_quick(const Aabb& box) const override {
        ++*tests_;
        return inner_->test_box_quick(box);
    }

private:
    std::unique_ptr<RegionVisibility> inner_;
    int* builds_;
    int* tests_;
};

/// Two managers over the same table and the same wandering entities: one takes the
/// bulk path (the table says every prepared test is its coarse one), the other asks
/// entity by entity. Boxes set after begin_update() (no preparation), entities that
/// leave and join (some after begin_update(), as the slots grow) and the cheapest
/// effort are mixed in. Every decision must be the same. With `scene`, the exact
/// stages answer where the table does not cover (`where_uncovered`), and must be
/// asked as often by both.
void expect_bulk_answers_are_one_by_one(std::shared_ptr<const CellVisibilityTable> table,
                                        const Aabb& area,
                                        std::shared_ptr<const OccluderScene> scene) {
    using NextFor = BakedRegionVisibility::NextFor;
    const RegionVisibilityFactory exact =
        scene ? occluder_region_visibility(scene) : RegionVisibilityFactory{};
    int builds[2] = {0, 0};
    int tests[2] = {0, 0};
    const auto next = [&](int k) -> std::unique_ptr<RegionVisibility> {
        return exact ? std::make_unique<CountingNext>(exact(), &builds[k], &tests[k]) : nullptr;
    };
    const NextFor next_for = scene ? NextFor::where_uncovered : NextFor::after_table;
    ASSERT_TRUE(BakedRegionVisibility(table, next(0), next_for).prepared_tests_are_coarse());
    ASSERT_FALSE(OneByOne(table, next(1), next_for).prepared_tests_are_coarse());
    builds[0] = builds[1] = tests[0] = tests[1] = 0;
    DSOCConfig config;
    config.validate_state = true;
    const Aabb world = table->grid().bounds();
    InterestManager bulk(config, world, [&]() -> std::unique_ptr<RegionVisibility> {
        return std::make_unique<BakedRegionVisibility>(table, next(0), next_for);
    });
    InterestManager one(config, world, [&]() -> std::unique_ptr<RegionVisibility> {
        return std::make_unique<OneByOne>(table, next(1), next_for);
    });
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_real_distribution<float> step(-6.0f, 6.0f);
    const glm::vec3 half{15.0f, 15.0f, 28.0f};
    const auto inside = [&](glm::vec3 c) {
        return glm::clamp(c, area.min + half, glm::max(area.min + half, area.max - half));
    };
    constexpr EntityId kEntities = 40;
    std::map<EntityId, glm::vec3> centre; // the live entities
    const auto join = [&](EntityId id) {
        centre[id] = inside(area.min + area.size() * glm::vec3(unit(rng), unit(rng), unit(rng)));
        const Aabb box = Aabb::from_center_half_extents(centre[id], half);
        ASSERT_TRUE(bulk.add_entity(id, EntityDesc{half, {}}, box));
        ASSERT_TRUE(one.add_entity(id, EntityDesc{half, {}}, box));
    };
    for (EntityId id = 1; id <= kEntities; ++id) {
        join(id);
    }
    for (ClientId c = 1; c <= 6; ++c) {
        ClientDesc d;
        d.viewer = static_cast<EntityId>(c * 6);
        ASSERT_TRUE(bulk.add_client(c, d));
        ASSERT_TRUE(one.add_client(c, d));
    }
    const auto move = [&](EntityId id) {
        centre[id] = inside(centre[id] + glm::vec3(step(rng), step(rng), 0.0f));
        const Aabb box = Aabb::from_center_half_extents(centre[id], half);
        ASSERT_TRUE(bulk.set_entity_box(id, box));
        ASSERT_TRUE(one.set_entity_box(id, box));
    };
    std::size_t visible = 0;
    std::size_t hidden = 0;
    EntityId next_id = kEntities + 1;
    for (std::uint64_t tick = 1; tick <= 150; ++tick) {
        if (tick % 15 == 0) { // one leaves (never a viewer): its slot is reused
            const EntityId gone = static_cast<EntityId>(1 + 6 * (tick / 15) % 35);
            if (gone % 6 != 0 && centre.erase(gone) == 1) {
                ASSERT_TRUE(bulk.remove_entity(gone));
                ASSERT_TRUE(one.remove_entity(gone));
            }
        }
        for (const auto& [id, c] : centre) {
            move(id);
        }
        bulk.begin_update(tick);
        one.begin_update(tick);
        if (tick % 5 == 0) {
            for (EntityId id = 1; id <= kEntities; id += 7) {
                if (centre.contains(id)) {
                    move(id); // after begin_update(): a box with no preparation
                }
            }
        }
        if (tick % 10 == 0) {
            join(next_id++); // after begin_update(): a slot with no preparation
        }
        for (std::size_t i = 0; i < bulk.client_count(); ++i) {
            const UpdateEffort effort =
                (tick + i) % 3 == 0 ? UpdateEffort::cheapest : UpdateEffort::full;
            bulk.update_client(i, effort);
            one.update_client(i, effort);
            const ClientId c = bulk.client_at(i);
            ASSERT_EQ(one.client_at(i), c);
            const ClientDecisions& a = *bulk.decisions(c);
            const ClientDecisions& o = *one.decisions(c);
            ASSERT_EQ(a.replicated.size(), o.replicated.size()) << "tick " << tick;
            for (std::size_t k = 0; k < a.replicated.size(); ++k) {
                ASSERT_EQ(a.replicated[k].id, o.replicated[k].id) << "tick " << tick;
                ASSERT_EQ(a.replicated[k].update_interval, o.replicated[k].update_interval);
            }
            ASSERT_EQ(a.enter, o.enter) << "tick " << tick;
            ASSERT_EQ(a.leave, o.leave) << "tick " << tick;
            ASSERT_EQ(bulk.stats(c)->box_tests, one.stats(c)->box_tests);
            visible += a.replicated.size();
            hidden += centre.size() - a.replicated.size();
        }
        bulk.require_valid_state("at tick " + std::to_string(tick));
        one.require_valid_state("at tick " + std::to_string(tick));
    }
    EXPECT_GT(hidden, 500u) << "the table hides something";
    EXPECT_GT(visible, 500u);
    // Built as lazily by both (the bulk pass also asks about the viewer's own box, so
    // it may test a little more).
    EXPECT_EQ(builds[0], builds[1]);
    EXPECT_GE(tests[0], tests[1]);
    if (scene) {
        EXPECT_GT(tests[1], 100) << "the exact stages answered what the table does not cover";
        EXPECT_GT(builds[1], 10);
    }
}

TEST(BakedRegionVisibility, TheManagersBulkAnswersAreItsOneByOneAnswers) {
    const Baked& b = corridor_table();
    expect_bulk_answers_are_one_by_one(b.table, b.play_area, nullptr);
}

/// The corridor's table with the lower half of x uncovered.
std::shared_ptr<const CellVisibilityTable> half_covered_table() {
    static const auto half = [] {
        const Baked& b = corridor_table();
        const CellGrid& grid = b.table->grid();
        std::vector<std::uint8_t> covered(grid.cell_count(), 0);
        for (std::uint32_t i = 0; i < grid.cell_count(); ++i) {
            covered[i] = grid.coords(i).x >= grid.dims.x / 2 ? 1 : 0;
        }
        CellBakeConfig config;
        config.cell_size = grid.cell_size;
        config.threads = 2;
        return std::make_shared<const CellVisibilityTable>(
            bake_cell_visibility(*b.scene, grid, config, nullptr, nullptr, {}, covered));
    }();
    return half;
}

/// `table` alone, with the exact stages over `scene` where it does not cover, counting
/// their builds and tests; its unions built from block unions where they can be, as
/// with_baked_stage() makes them.
std::unique_ptr<BakedRegionVisibility>
table_alone_counting(std::shared_ptr<const CellVisibilityTable> table,
                     std::shared_ptr<const OccluderScene> scene, int& builds, int& tests) {
    auto blocks = std::make_shared<const CellBlockUnions>(*table);
    return std::make_unique<BakedRegionVisibility>(
        std::move(table),
        std::make_unique<CountingNext>(occluder_region_visibility(std::move(scene))(), &builds,
                                       &tests),
        BakedRegionVisibility::NextFor::where_uncovered, std::move(blocks));
}

TEST(BakedRegionVisibility, BehindTheTableAloneTheExactStagesAnswerOnlyWhereItDoesNotCover) {
    // The corridor's table with the lower half of x uncovered: what touches it is asked
    // of the exact stages, built only when needed; the rest is the table's answer.
    const Baked& b = corridor_table();
    const CellGrid& grid = b.table->grid();
    const auto half = half_covered_table();
    ASSERT_GT(half->uncovered_cells().size(), 0u);
    // A covered region and covered boxes never build the exact stages.
    int builds = 0;
    int tests = 0;
    const auto owned = table_alone_counting(half, b.scene, builds, tests);
    BakedRegionVisibility& stage = *owned;
    // The covered half of the play area, a cell clear of the uncovered one.
    Aabb right = b.play_area;
    right.min.x = std::max(right.min.x, grid.origin.x + static_cast<float>(grid.dims.x / 2 + 1) *
                                                            grid.cell_size);
    ASSERT_LT(right.min.x + 60.0f, right.max.x);
    std::mt19937 rng(3);
    std::vector<std::int32_t> words;
    std::vector<std::int32_t> runs;
    int table_answers = 0;
    for (int r = 0; r < 40; ++r) {
        const Aabb region = random_box(rng, right, 16.0f, 40.0f);
        const Aabb box = random_box(rng, right, 16.0f, 40.0f);
        stage.build(region);
        if (!stage.active() || !half->open_words_of(box, words, runs)) {
            continue;
        }
        (void)stage.test_box(box);
        ++table_answers;
        EXPECT_FALSE(stage.next_built());
    }
    EXPECT_GT(table_answers, 10);
    EXPECT_EQ(builds, 0);
    EXPECT_EQ(tests, 0);
    expect_bulk_answers_are_one_by_one(half, b.play_area, b.scene);
}

/// Whether some covered open cell of `region` may see some open cell of `box` by the
/// table, cell pair by cell pair: the slow twin of a partial region's union.
bool covered_cells_may_see(const CellVisibilityTable& table, const Aabb& region, const Aabb& box) {
    const auto open_cells = [&table](const Aabb& b) {
        std::vector<OpenCell> cells;
        glm::ivec3 lo;
        glm::ivec3 hi;
        if (table.grid().range_of(b, lo, hi)) {
            for (int z = lo.z; z <= hi.z; ++z) {
                for (int y = lo.y; y <= hi.y; ++y) {
                    for (int x = lo.x; x <= hi.x; ++x) {
                        const OpenCell c = table.open_index(table.grid().index({x, y, z}));
                        if (c >= 0) {
                            cells.push_back(c);
                        }
                    }
                }
            }
        }
        return cells;
    };
    for (const OpenCell from : open_cells(region)) {
        for (const OpenCell to : open_cells(box)) {
            if (table.may_see(from, to)) {
                return true;
            }
        }
    }
    return false;
}

TEST(BakedRegionVisibility, APartialRegionKeepsTheTablesVisibleAndAsksTheExactStagesTheRest) {
    // Behind the table alone, a region with cells on both sides of the covered half:
    // a box an eye of its covered cells may see is visible by the table, unasked; a
    // box hidden from all of them is the exact stages' to answer (an eye of the
    // uncovered cells may see it). Nothing called hidden is reached by a segment.
    const Baked& b = corridor_table();
    const auto half = half_covered_table();
    const ReferenceVisibility reference(b.scene->world);
    int builds = 0;
    int tests = 0;
    const auto owned = table_alone_counting(half, b.scene, builds, tests);
    BakedRegionVisibility& stage = *owned;
    const auto exact = occluder_region_visibility(b.scene)();
    std::mt19937 rng(23);
    std::vector<std::int32_t> words;
    std::vector<std::int32_t> runs;
    int partial_regions = 0;
    int from_blocks = 0; // partial regions whose union was built from block unions
    int seen_by_table = 0;
    int asked = 0;
    int hidden = 0;
    int clear = 0;
    for (int r = 0; r < 400 && partial_regions < 40; ++r) {
        const Aabb region = random_box(rng, b.play_area, 40.0f, 160.0f);
        stage.build(region);
        if (!stage.partial()) {
            continue;
        }
        ++partial_regions;
        EXPECT_FALSE(stage.active());
        glm::ivec3 lo;
        glm::ivec3 hi;
        ASSERT_TRUE(half->grid().range_of(region, lo, hi));
        from_blocks += CellBlockUnions::covers(lo, hi) ? 1 : 0;
        exact->build(region);
        for (int k = 0; k < 30; ++k) {
            const Aabb box = random_box(rng, b.play_area, 16.0f, 64.0f);
            if (!half->open_words_of(box, words, runs)) {
                continue; // a box the table does not cover: the exact stages', as before
            }
            const int tests_before = tests;
            const Visibility v = stage.test_box(box);
            PreparedBox p;
            stage.prepare(box, p);
            ASSERT_EQ(stage.test_prepared_coarse(p), v);
            if (covered_cells_may_see(*half, region, box)) {
                EXPECT_EQ(v, Visibility::visible);
                EXPECT_EQ(tests, tests_before) << "the table's visible was asked again";
                ++seen_by_table;
                continue;
            }
            ++asked;
            EXPECT_EQ(v, exact->test_box(box)) << "the exact stages' answer";
            if (v != Visibility::occluded) {
                continue;
            }
            ++hidden;
            clear += clear_segments(reference, region, box, rng);
        }
    }
    EXPECT_GE(partial_regions, 20);
    EXPECT_GE(from_blocks, 10);
    EXPECT_GT(seen_by_table, 50) << "boxes the exact stages were spared";
    EXPECT_GT(asked, 20);
    EXPECT_GT(hidden, 5) << "something is culled";
    EXPECT_EQ(clear, 0) << "clear segments into boxes called hidden";
    EXPECT_GT(builds, 0);
}

} // namespace
} // namespace dsoc::visibility
