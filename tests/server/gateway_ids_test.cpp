// A gateway's ids and the rules that repair lost joins and leaves (GatewayIds), tick by
// tick on a fake clock: a join is sent again only when a tick lacks its player a whole
// kResendAfter after it was sent, a leave only while a tick still shows the player that
// long after; ids the gateway did not give out are never sent.

#include "dsoc/server/gateway_ids.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace dsoc::server {
namespace {

using namespace std::chrono_literals;
using Ids = std::vector<std::uint32_t>;

/// A tick's entities: bots 1..3 and the players `players` (increasing).
std::vector<interest::Entity> tick_with(const Ids& players) {
    std::vector<interest::Entity> out;
    for (std::uint32_t id = 1; id <= 3; ++id) {
        out.push_back(interest::Entity{.id = id, .kind = interest::EntityKind::bot});
    }
    for (const std::uint32_t id : players) {
        out.push_back(interest::Entity{.id = id, .kind = interest::EntityKind::player});
    }
    return out;
}

class GatewayIdsTest : public ::testing::Test {
protected:
    void SetUp() override { ids_.add_block(10, 4); }
    GatewayIds::Resend check(const Ids& players) { return ids_.check(tick_with(players), now_); }

    GatewayIds ids_;
    GatewayIds::Clock::time_point now_{std::chrono::hours(1)};
};

TEST_F(GatewayIdsTest, AJoinIsSentAgainWhenATickLacksItsPlayerAfterItsTime) {
    const std::uint32_t a = ids_.take();
    const std::uint32_t b = ids_.take();
    EXPECT_EQ(a, 10u);
    EXPECT_EQ(ids_.join(Ids{a, b}, now_), (Ids{a, b}));
    now_ += 500ms;
    EXPECT_TRUE(check({}).joins.empty()); // on its way still
    now_ += 500ms;
    EXPECT_TRUE(check({a, b}).joins.empty()); // arrived
    now_ += 2s;
    EXPECT_TRUE(check({a, b}).joins.empty());
    // The world removed b (it took this gateway for lost): sent again at once, then not
    // before its time again.
    EXPECT_EQ(check({a}).joins, (Ids{b}));
    now_ += 999ms;
    EXPECT_TRUE(check({a}).joins.empty());
    now_ += 1ms;
    EXPECT_EQ(check({a}).joins, (Ids{b}));
    EXPECT_TRUE(check({a}).leaves.empty());
}

TEST_F(GatewayIdsTest, ALeaveIsSentAgainWhileATickShowsThePlayerAfterItsTime) {
    const std::uint32_t a = ids_.take();
    (void)ids_.join(Ids{a}, now_);
    EXPECT_EQ(ids_.leave(Ids{a}, now_), (Ids{a}));
    now_ += 100ms;
    EXPECT_TRUE(check({a}).leaves.empty()); // a tick taken before the world had it
    now_ += 900ms;
    EXPECT_EQ(check({a}).leaves, (Ids{a})); // lost
    now_ += 500ms;
    EXPECT_TRUE(check({a}).leaves.empty());
    now_ += 500ms;
    EXPECT_EQ(check({a}).leaves, (Ids{a}));
    now_ += 1s;
    EXPECT_TRUE(check({}).leaves.empty()); // gone
    // A ghost that shows again (a join that was still on its way) goes at once.
    EXPECT_EQ(check({a}).leaves, (Ids{a}));
    EXPECT_TRUE(check({a}).joins.empty()); // a left player is never joined again
}

TEST_F(GatewayIdsTest, OnlyIdsItGaveOutAreSentAndAClearForgetsThemAll) {
    const std::uint32_t a = ids_.take();
    EXPECT_TRUE(ids_.join(Ids{a + 1, 99, 3}, now_).empty()); // not given out; not ours; a bot's
    EXPECT_TRUE(ids_.leave(Ids{a + 1, 99}, now_).empty());
    now_ += 5s;
    // Neither are another gateway's players, nor bots, taken for ghosts.
    EXPECT_TRUE(check({20, 21}).leaves.empty());
    EXPECT_EQ(ids_.left(), 3u);

    (void)ids_.join(Ids{a}, now_);
    ids_.clear(); // a new world instance: these ids mean nothing to it
    EXPECT_EQ(ids_.left(), 0u);
    EXPECT_EQ(ids_.take(), 0u);
    now_ += 5s;
    const GatewayIds::Resend after = check({a});
    EXPECT_TRUE(after.joins.empty());
    EXPECT_TRUE(after.leaves.empty());
    EXPECT_TRUE(ids_.leave(Ids{a}, now_).empty());
    ids_.add_block(10, 4);                         // the new world hands out the same numbers
    EXPECT_TRUE(ids_.leave(Ids{a}, now_).empty()); // not given out in it yet
    EXPECT_EQ(ids_.take(), a);
    EXPECT_EQ(ids_.join(Ids{a}, now_), (Ids{a}));
}

} // namespace
} // namespace dsoc::server
