// The compressed rows against the dense rows they were made from (the slow, obviously
// correct twin), the block unions against the rows they unite, and the block-order runs
// of a box against the cells it touches.

#include "dsoc/visibility/cell_block_unions.hpp"
#include "dsoc/visibility/cell_visibility.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <random>
#include <set>

namespace dsoc::visibility {
namespace {

/// A random table over a grid of odd sizes (blocks cut at the edges), about a third of
/// the cells solid, visibility falling off with distance so that whole words are
/// hidden, whole words visible and the rest mixed, as in a baked map. With
/// `uncovered_top`, the cells of the top layer and of one column that are not solid are
/// uncovered (as above a map's player space).
CellVisibilityTable random_table(std::mt19937& random, glm::ivec3 dims,
                                 bool uncovered_top = false) {
    CellGrid grid;
    grid.cell_size = 16.0f;
    grid.origin = {-100.0f, 7.0f, 0.0f};
    grid.dims = dims;
    std::vector<std::uint32_t> open;
    std::vector<std::uint32_t> uncovered;
    std::bernoulli_distribution solid(0.35);
    for (std::uint32_t i = 0; i < grid.cell_count(); ++i) {
        if (!solid(random)) {
            const glm::ivec3 c = grid.coords(i);
            const bool out = uncovered_top && (c.z == dims.z - 1 || (c.x == 3 && c.y == 4));
            (out ? uncovered : open).push_back(i);
        }
    }
    std::ranges::shuffle(open, random); // the table numbers them itself
    std::ranges::shuffle(uncovered, random);
    CellVisibilityTable table(grid, open, uncovered);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const auto n = static_cast<OpenCell>(table.open_count());
    for (OpenCell a = 0; a < n; ++a) {
        const glm::vec3 pa = grid.coords(table.open_cells()[static_cast<std::size_t>(a)]);
        for (OpenCell b = a; b < n; ++b) {
            const glm::vec3 pb = grid.coords(table.open_cells()[static_cast<std::size_t>(b)]);
            const float d = glm::length(pa - pb);
            if (a == b || d < 6.0f || (d < 10.0f && unit(random) < 0.5f)) {
                table.set_visible_atomic(a, b);
            }
        }
    }
    return table;
}

TEST(CellVisibilityTable, CompressedRowsGiveTheDenseRowsAnswers) {
    std::mt19937 random(1234);
    // The last grid's rows span several class words (32 row words each), a quarter of
    // them with literal words in two or more, as a real map's rows do.
    for (const glm::ivec3 dims : {glm::ivec3{13, 9, 6}, glm::ivec3{4, 4, 4}, glm::ivec3{1, 30, 3},
                                  glm::ivec3{21, 17, 5}, glm::ivec3{40, 30, 6}}) {
        CellVisibilityTable dense = random_table(random, dims);
        CellVisibilityTable packed = dense;
        packed.compress();
        ASSERT_TRUE(packed.compressed());
        const auto n = static_cast<OpenCell>(dense.open_count());
        std::uint64_t visible_words = 0;
        std::uint64_t hidden_words = 0;
        std::uint64_t rows_with_literals_in_two_class_words = 0;
        for (OpenCell a = 0; a < n; ++a) {
            std::vector<std::uint64_t> d(dense.words_per_row(), 0);
            std::vector<std::uint64_t> p(dense.words_per_row(), 1); // bit 0: a real cell
            dense.or_row_into(a, d);
            packed.or_row_into(a, p); // ORs into what is there
            std::set<std::size_t> class_words_with_literals;
            for (std::size_t w = 0; w < d.size(); ++w) {
                ASSERT_EQ(p[w], d[w] | 1u) << "row " << a << " word " << w;
                hidden_words += d[w] == 0 ? 1 : 0;
                visible_words += d[w] == ~std::uint64_t{0} ? 1 : 0;
                if (d[w] != 0 && d[w] != ~std::uint64_t{0}) {
                    class_words_with_literals.insert(w / 32);
                }
            }
            rows_with_literals_in_two_class_words += class_words_with_literals.size() >= 2 ? 1 : 0;
            for (OpenCell b = 0; b < n; ++b) {
                ASSERT_EQ(packed.may_see(a, b), dense.may_see(a, b)) << a << " " << b;
            }
        }
        EXPECT_EQ(packed.hidden_pairs(), dense.hidden_pairs());
        if (n > 512) {
            EXPECT_GT(dense.hidden_pairs(), 0u); // something is hidden
            EXPECT_GT(hidden_words, 0u);         // every kind of word was exercised
            EXPECT_GT(visible_words, 0u);
            EXPECT_LT(packed.memory_bytes(), dense.memory_bytes());
        }
        if (dense.words_per_row() > 64) {
            EXPECT_GT(rows_with_literals_in_two_class_words, static_cast<std::uint64_t>(n / 4));
        }
    }
}

TEST(CellBlockUnions, ARangesUnionFromBlocksIsTheUnionOfItsCellsRows) {
    std::mt19937 random(4321);
    for (const glm::ivec3 dims : {glm::ivec3{13, 9, 6}, glm::ivec3{2, 2, 2}, glm::ivec3{1, 30, 3},
                                  glm::ivec3{40, 30, 6}, glm::ivec3{70, 3, 2}}) {
        CellVisibilityTable table = random_table(random, dims, true);
        for (const bool compressed : {false, true}) {
            if (compressed) {
                table.compress();
            }
            const CellBlockUnions blocks(table);
            const CellGrid& grid = table.grid();
            std::uniform_int_distribution<int> x(0, dims.x - 1);
            std::uniform_int_distribution<int> y(0, dims.y - 1);
            std::uniform_int_distribution<int> z(0, dims.z - 1);
            std::uniform_int_distribution<int> cells(2, 8);
            int ranges = 0;
            int odd = 0;           // ranges with an odd number of cells on an axis
            int partly_hidden = 0; // unions with a hidden open cell: something is culled
            for (int k = 0; k < 3000; ++k) {
                // Ranges of two to eight cells an axis, as eye regions are, some cut
                // at the grid's edge.
                const glm::ivec3 lo{x(random), y(random), z(random)};
                const glm::ivec3 hi = glm::min(
                    lo + glm::ivec3{cells(random), cells(random), cells(random)} - 1, dims - 1);
                if (!CellBlockUnions::covers(lo, hi)) {
                    continue;
                }
                ++ranges;
                const glm::ivec3 n = hi - lo + 1;
                odd += (n.x % 2) + (n.y % 2) + (n.z % 2) > 0 ? 1 : 0;
                std::vector<std::uint64_t> rows(table.words_per_row(), 0);
                for (int cz = lo.z; cz <= hi.z; ++cz) {
                    for (int cy = lo.y; cy <= hi.y; ++cy) {
                        for (int cx = lo.x; cx <= hi.x; ++cx) {
                            const OpenCell c = table.open_index(grid.index({cx, cy, cz}));
                            if (c >= 0) {
                                table.or_row_into(c, rows);
                            }
                        }
                    }
                }
                std::vector<std::uint64_t> from_blocks(table.words_per_row(), 0);
                blocks.or_range_into(lo, hi, from_blocks);
                ASSERT_EQ(from_blocks, rows) << "cells " << lo.x << "," << lo.y << "," << lo.z
                                             << " to " << hi.x << "," << hi.y << "," << hi.z;
                std::size_t seen = 0;
                for (const std::uint64_t w : rows) {
                    seen += static_cast<std::size_t>(std::popcount(w));
                }
                partly_hidden += seen < table.open_count() ? 1 : 0;
            }
            if (dims.x * dims.y * dims.z > 500) {
                EXPECT_GT(ranges, 200) << dims.x;
                EXPECT_GT(odd, ranges / 2) << dims.x;
                EXPECT_GT(partly_hidden, ranges / 3) << dims.x;
            }
            if (glm::any(glm::lessThan(dims, glm::ivec3(2)))) {
                EXPECT_EQ(ranges, 0);
                EXPECT_EQ(blocks.block_count(), 0u);
            }
        }
    }
}

TEST(CellVisibilityTable, RunsAndWordsOfABoxAreExactlyItsOpenCells) {
    std::mt19937 random(99);
    const CellVisibilityTable table = random_table(random, {19, 11, 7}, true);
    ASSERT_GT(table.uncovered_cells().size(), 100u);
    const CellGrid& grid = table.grid();
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<std::int32_t> runs;
    std::vector<std::int32_t> words;
    std::vector<std::int32_t> scratch;
    int answered = 0;
    int refused_uncovered = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const glm::vec3 size = grid.bounds().size();
        glm::vec3 a = grid.bounds().min + size * glm::vec3(u(random), u(random), u(random));
        glm::vec3 b = a + glm::vec3(u(random), u(random), u(random)) * 60.0f;
        const Aabb box{glm::min(a, b), glm::max(a, b)};
        glm::ivec3 lo;
        glm::ivec3 hi;
        const bool covered = grid.range_of(box, lo, hi);
        const bool answer = table.open_runs_of(box, runs);
        ASSERT_EQ(table.open_words_of(box, words, scratch), answer);
        if (!covered) {
            EXPECT_FALSE(answer);
            continue;
        }
        std::set<std::int32_t> expected;
        bool touches_uncovered = false;
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                for (int x = lo.x; x <= hi.x; ++x) {
                    const OpenCell c = table.open_index(grid.index({x, y, z}));
                    if (c >= 0) {
                        expected.insert(c);
                    }
                    touches_uncovered |= c == kUncoveredCell;
                }
            }
        }
        // A box touching an uncovered cell is never answered, whatever else it holds.
        ASSERT_EQ(answer, !touches_uncovered && !expected.empty());
        if (touches_uncovered) {
            ++refused_uncovered;
            continue;
        }
        std::set<std::int32_t> got;
        for (std::size_t k = 0; k + 1 < runs.size(); k += 2) {
            ASSERT_LT(runs[k], runs[k + 1]);
            if (k > 0) {
                ASSERT_GT(runs[k], runs[k - 1]) << "runs must be sorted and joined";
            }
            for (std::int32_t c = runs[k]; c < runs[k + 1]; ++c) {
                got.insert(c);
            }
        }
        ASSERT_EQ(got, expected);
        std::set<std::int32_t> from_words; // triples (word, low 32 bits, high 32 bits)
        for (std::size_t k = 0; k + 2 < words.size(); k += 3) {
            ASSERT_TRUE(k == 0 || words[k - 3] < words[k]) << "one triple per word, increasing";
            const std::uint64_t mask = static_cast<std::uint32_t>(words[k + 1]) |
                                       std::uint64_t{static_cast<std::uint32_t>(words[k + 2])}
                                           << 32;
            ASSERT_NE(mask, 0u);
            for (int bit = 0; bit < 64; ++bit) {
                if ((mask >> bit & 1u) != 0) {
                    from_words.insert(words[k] * 64 + bit);
                }
            }
        }
        ASSERT_EQ(from_words, expected);
        answered += answer ? 1 : 0;
    }
    EXPECT_GT(answered, 500);
    EXPECT_GT(refused_uncovered, 100);
}

} // namespace
} // namespace dsoc::visibility
