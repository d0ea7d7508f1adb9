// A gateway's ids and the rules that repair lost joins and leaves (GatewayIds), tick by
// tick on a fake clock: a join is sent again only when a tick lacks its player a whole
// kResendAfter after it was sent, a leave while a tick still shows the player that long
// after, or, when no tick showed it, a bounded number of times; ids the gateway did not
// give out are never sent; a join no tick shows after its bounded re-sends is given up
// with the rest of its block (the world forgot the gateway). And how many ids it asks
// for: more after a world restart (its players come back together) and when hellos
// found none left.

#include "dsoc/server/gateway_ids.hpp"

#include "dsoc/scaleout/world_messages.hpp"

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
    // Neither are another gateway's players, nor bots, nor an id of our block not
    // handed out yet, taken for ghosts.
    EXPECT_TRUE(check({a + 1, 20, 21}).leaves.empty());
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

TEST_F(GatewayIdsTest, ALeaveNoTickShowedIsSentAgainABoundedNumberOfTimes) {
    // a: joined, but its join was lost (no tick ever shows it); b: given out, its client
    // gone before its first tick (never joined). The world keeps both reserved for this
    // gateway until a leave arrives, and no tick can acknowledge one.
    const std::uint32_t a = ids_.take();
    const std::uint32_t b = ids_.take();
    (void)ids_.join(Ids{a}, now_);
    now_ += 100ms;
    EXPECT_TRUE(check({}).joins.empty());
    EXPECT_EQ(ids_.leave(Ids{a, b}, now_), (Ids{a, b}));
    int resent = 0;
    for (int i = 0; i < 3 * GatewayIds::kBlindResends; ++i) {
        now_ += 500ms;
        const GatewayIds::Resend resend = check({});
        EXPECT_TRUE(resend.joins.empty()); // a left player is never joined again
        if (!resend.leaves.empty()) {
            EXPECT_EQ(resend.leaves, (Ids{a, b})) << i;
            ++resent;
        }
    }
    EXPECT_EQ(resent, GatewayIds::kBlindResends); // each a whole kResendAfter apart
}

TEST_F(GatewayIdsTest, ALeaveShownByATickIsResentWhileShownNotBlind) {
    const std::uint32_t a = ids_.take();
    (void)ids_.join(Ids{a}, now_);
    now_ += 100ms;
    (void)check({a}); // the world has it
    (void)ids_.leave(Ids{a}, now_);
    now_ += 1s;
    EXPECT_TRUE(check({}).leaves.empty()); // gone: the tick acknowledged the leave
    now_ += 5s;
    EXPECT_TRUE(check({}).leaves.empty());

    // A blind leave whose player a tick shows after all (its join was on its way) is
    // sent again while the ticks show it, then no more once they do not.
    const std::uint32_t b = ids_.take();
    (void)ids_.join(Ids{b}, now_);
    (void)ids_.leave(Ids{b}, now_);
    now_ += 1s;
    EXPECT_EQ(check({b}).leaves, (Ids{b}));
    now_ += 1s;
    EXPECT_EQ(check({b}).leaves, (Ids{b}));
    now_ += 1s;
    EXPECT_TRUE(check({}).leaves.empty());
    now_ += 1s;
    EXPECT_TRUE(check({}).leaves.empty());
}

TEST_F(GatewayIdsTest, AJoinNoTickShowsAfterItsResendsIsGivenUpWithTheRestOfItsBlock) {
    // A world that forgot this gateway (it took it for lost, then needed the room) no
    // longer holds its ids: a re-join is refused however often it comes.
    ids_.add_block(20, 4); // a block asked for after the world forgot the gateway
    const std::uint32_t a = ids_.take();
    const std::uint32_t b = ids_.take();
    (void)ids_.join(Ids{a, b}, now_);
    now_ += 1s;
    (void)check({a, b}); // both in the world
    int resent = 0;
    GatewayIds::Resend last;
    for (int i = 0; i < 3 * GatewayIds::kJoinResends && last.abandoned.empty(); ++i) {
        now_ += 1s;
        // b shows again now and then (the world had only lost it for a while): its
        // re-sends count afresh each time.
        last = check(i % 2 == 0 ? Ids{} : Ids{b});
        resent += last.joins == Ids{a} || last.joins == Ids{a, b} ? 1 : 0;
    }
    EXPECT_EQ(resent, GatewayIds::kJoinResends);
    EXPECT_EQ(last.abandoned, (Ids{a}));
    EXPECT_EQ(last.leaves, (Ids{a})); // should the world hold it after all, released
    EXPECT_TRUE(last.joins.empty());
    // The rest of a's block is void too (reserved before the world forgot the gateway);
    // the later block is kept.
    EXPECT_EQ(last.voided, 2u);
    EXPECT_EQ(ids_.left(), 4u);
    EXPECT_EQ(ids_.take(), 20u);
    // Given up for good: never joined again, and its leave sent blind a bounded number of
    // times.
    int leaves = 0;
    for (int i = 0; i < 3 * GatewayIds::kBlindResends; ++i) {
        now_ += 1s;
        const GatewayIds::Resend resend = check({b});
        EXPECT_TRUE(resend.joins.empty()) << i;
        EXPECT_TRUE(resend.abandoned.empty()) << i;
        leaves += resend.leaves == Ids{a} ? 1 : 0;
    }
    EXPECT_EQ(leaves, GatewayIds::kBlindResends);
}

TEST(GatewayIdsDemand, ABlockAfterAClearCoversThePlayersThatHeldIds) {
    GatewayIds ids;
    EXPECT_EQ(ids.to_reserve(), GatewayIds::kIdBlock); // none yet
    ids.add_block(100, 1000);
    EXPECT_EQ(ids.to_reserve(), 0u);
    Ids taken;
    for (int i = 0; i < 700; ++i) {
        taken.push_back(ids.take());
    }
    (void)ids.leave(std::span(taken).first(100), GatewayIds::Clock::now());
    EXPECT_EQ(ids.to_reserve(), 0u); // 300 left
    // A world restart: the 600 sessions that held an id end, and their clients come
    // back together: one request covers them, and a block more.
    ids.clear();
    EXPECT_EQ(ids.to_reserve(), 600u + GatewayIds::kIdBlock);
    ids.add_block(5000, 600 + GatewayIds::kIdBlock);
    EXPECT_EQ(ids.to_reserve(), 0u);

    // Never more than one request may carry.
    ids.add_block(10'000, scaleout::kMaxIdBlock);
    for (std::uint32_t i = 0; i < 2 * scaleout::kMaxIdBlock; ++i) {
        (void)ids.take();
    }
    ids.clear();
    EXPECT_EQ(ids.to_reserve(), scaleout::kMaxIdBlock);
}

TEST(GatewayIdsDemand, PlayersWhoseJoinsWereGivenUpAreWantedAgain) {
    GatewayIds ids;
    ids.add_block(100, 300);
    Ids players;
    for (int i = 0; i < 300; ++i) {
        players.push_back(ids.take());
    }
    auto now = GatewayIds::Clock::now();
    (void)ids.join(players, now);
    EXPECT_EQ(ids.to_reserve(), GatewayIds::kIdBlock);
    GatewayIds::Resend resend;
    for (int i = 0; i <= GatewayIds::kJoinResends; ++i) {
        now += GatewayIds::kResendAfter;
        resend = ids.check({}, now); // the world forgot this gateway
    }
    EXPECT_EQ(resend.abandoned, players);
    // Their clients come back together: one request covers them, and a block more.
    EXPECT_EQ(ids.to_reserve(), 300u + GatewayIds::kIdBlock);
}

TEST(GatewayIdsDemand, HellosThatFoundNoIdMakeTheNextRequestLarger) {
    GatewayIds ids;
    for (int i = 0; i < 1000; ++i) {
        EXPECT_EQ(ids.take(), 0u);
    }
    EXPECT_EQ(ids.to_reserve(), 1000u + GatewayIds::kIdBlock);
    ids.add_block(1, GatewayIds::kIdBlock); // the request sent before they came
    EXPECT_EQ(ids.to_reserve(), 744u);      // 488 short, and a block more
}

} // namespace
} // namespace dsoc::server
