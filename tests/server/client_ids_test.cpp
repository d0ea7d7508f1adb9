// Client ids past their 32 bits: the ones still held are skipped, and so is 0.

#include "dsoc/server/client_ids.hpp"

#include <gtest/gtest.h>

#include <set>

namespace dsoc::server {
namespace {

TEST(ClientIds, AfterTheyWrapTheIdsStillHeldAndZeroAreSkipped) {
    const std::set<std::uint32_t> held{0xffffffffu, 1, 2, 5};
    const auto in_use = [&](std::uint32_t id) { return held.contains(id); };
    std::uint32_t next = 0xfffffffeu;
    EXPECT_EQ(take_free_client_id(next, in_use), 0xfffffffeu);
    EXPECT_EQ(take_free_client_id(next, in_use), 3u); // past 0xffffffff, 0, 1 and 2
    EXPECT_EQ(take_free_client_id(next, in_use), 4u);
    EXPECT_EQ(take_free_client_id(next, in_use), 6u);
    EXPECT_EQ(next, 7u);
}

} // namespace
} // namespace dsoc::server
