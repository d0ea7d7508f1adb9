#include "dsoc/protocol/flat_id_map.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>

namespace dsoc::protocol {
namespace {

/// Checks every entry of `m` against the obviously-correct `truth`, both ways.
void expect_same(const FlatIdMap<int>& m, const std::map<std::uint32_t, int>& truth) {
    ASSERT_EQ(m.size(), truth.size());
    for (const auto& [id, v] : truth) {
        const int* found = m.find(id);
        ASSERT_NE(found, nullptr) << "id " << id;
        EXPECT_EQ(*found, v) << "id " << id;
    }
    std::size_t visited = 0;
    m.for_each([&](std::uint32_t id, int v) {
        ++visited;
        const auto it = truth.find(id);
        ASSERT_NE(it, truth.end()) << "stray id " << id;
        EXPECT_EQ(it->second, v);
    });
    EXPECT_EQ(visited, truth.size());
}

// Random inserts and erases against std::map: dense ids (entities), a few far ones,
// and the edge values, so the probe runs wrap around the table and backward-shift
// deletion has to move entries across the end.
TEST(FlatIdMap, MatchesStdMapUnderRandomInsertsAndErases) {
    std::mt19937 rng(5);
    for (const std::uint32_t spread : {64u, 1024u, 0xffffffffu}) {
        FlatIdMap<int> m;
        std::map<std::uint32_t, int> truth;
        std::uniform_int_distribution<std::uint32_t> id(0, spread);
        for (int step = 0; step < 20000; ++step) {
            std::uint32_t key = id(rng);
            if (step % 97 == 0) {
                key = step % 2 == 0 ? 0u : 0xffffffffu;
            }
            if (rng() % 3 == 0) {
                EXPECT_EQ(m.erase(key), truth.erase(key) == 1) << "erase " << key;
            } else {
                const int value = static_cast<int>(rng() % 1000);
                const auto [stored, inserted] = m.try_emplace(key, value);
                const auto [it, truth_inserted] = truth.try_emplace(key, value);
                EXPECT_EQ(inserted, truth_inserted) << "insert " << key;
                EXPECT_EQ(*stored, it->second);
            }
            if (step % 1000 == 0) {
                expect_same(m, truth);
            }
        }
        expect_same(m, truth);
        for (std::uint32_t k = 0; k < 64; ++k) { // absent keys are absent
            if (!truth.contains(k)) {
                EXPECT_FALSE(m.contains(k)) << k;
            }
        }
    }
}

TEST(FlatIdMap, ClearKeepsNothingAndOperatorBracketValueInitializes) {
    FlatIdMap<int> m;
    for (std::uint32_t i = 0; i < 100; ++i) {
        m[i] = static_cast<int>(i) + 1;
    }
    EXPECT_EQ(m.size(), 100u);
    m.clear();
    EXPECT_TRUE(m.empty());
    EXPECT_EQ(m.find(5), nullptr);
    EXPECT_EQ(m[7], 0);
    EXPECT_EQ(m.size(), 1u);
    EXPECT_FALSE(m.erase(8));
}

} // namespace
} // namespace dsoc::protocol
