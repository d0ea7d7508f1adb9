// The world tick: a gateway's mirror of the world process's state reads exactly as the
// world does (the same entity views, eyes and respawns, and the same answers from a
// DSOC policy tick after tick), and bad bytes are refused with a reason, never trusted.

#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dsoc::scaleout {
namespace {

using interest::Entity;
using interest::GameWorld;
using interest::Interest;
using interest::WorldSettings;

WorldSettings busy_settings() {
    WorldSettings s;
    s.bots = 40;
    s.seed = 7;
    s.respawn_delay_ticks = 3; // pending respawns travel too
    s.teams = 2;
    s.sounds.bot_shots_per_second = 4.0f; // shots and deaths within a few seconds
    s.shots.damage = 50;
    return s;
}

std::vector<std::byte> tick_bytes(const GameWorld& world, std::uint64_t tick) {
    std::vector<std::byte> out;
    encode_world_tick(world, 42, tick, out);
    return out;
}

bool same_view(const interest::EntityView& a, const interest::EntityView& b) {
    return a.id == b.id && a.box.min == b.box.min && a.box.max == b.box.max &&
           a.velocity == b.velocity && a.arrival_eye == b.arrival_eye && a.team == b.team &&
           a.sound_range == b.sound_range;
}

TEST(WorldTick, AMirrorGivesTheWorldsAnswersTickAfterTick) {
    const auto map = testing::rooms_map();
    GameWorld world(busy_settings(), map);
    GameWorld mirror(busy_settings(), map);
    std::vector<std::uint32_t> players;
    for (int i = 0; i < 4; ++i) {
        players.push_back(world.spawn_player());
    }
    interest::PolicySettings settings;
    settings.policy = interest::PolicyKind::dsoc;
    settings.baked_stage = false; // a generated map has no table; the exact stages decide
    auto at_world = interest::make_policy(settings, world);
    auto at_mirror = interest::make_policy(settings, mirror);
    for (std::uint32_t v = 0; v < players.size(); ++v) {
        at_world->add_viewer(v, players[v]);
        at_mirror->add_viewer(v, players[v]);
    }
    std::size_t selected = 0;
    std::size_t pending_respawns = 0;
    for (std::uint64_t tick = 1; tick <= 90; ++tick) {
        for (std::uint32_t v = 0; v < players.size(); ++v) {
            world.set_player_input(players[v], glm::vec3(tick % 7 < 4 ? 1.0f : -1.0f, 0.3f, 0.0f),
                                   tick % 11 == 0, static_cast<float>(tick * 13 % 360) - 180.0f,
                                   5.0f);
        }
        world.step(1.0f / 30.0f);
        auto decoded = decode_world_tick(tick_bytes(world, tick), "test", 42);
        ASSERT_TRUE(decoded.ok()) << decoded.error().message();
        EXPECT_EQ(decoded->tick, tick);
        apply_world_tick(std::move(decoded).value(), mirror);

        ASSERT_EQ(mirror.entity_count(), world.entity_count());
        for (std::size_t i = 0; i < world.entity_count(); ++i) {
            ASSERT_TRUE(same_view(mirror.entity(i), world.entity(i))) << "entity " << i;
            pending_respawns += world.entities()[i].respawn ? 1 : 0;
        }
        EXPECT_EQ(mirror.frags(), world.frags());
        EXPECT_EQ(tick_bytes(mirror, tick), tick_bytes(world, tick)); // nothing lost or added

        at_world->begin_tick(world, tick);
        at_mirror->begin_tick(mirror, tick);
        for (std::uint32_t v = 0; v < players.size(); ++v) {
            const Entity& self = *world.find(players[v]);
            const Entity& mirrored = *mirror.find(players[v]);
            std::vector<Interest> from_world;
            std::vector<Interest> from_mirror;
            at_world->select(world, interest::viewer_of(world, v, self), from_world);
            at_mirror->select(mirror, interest::viewer_of(mirror, v, mirrored), from_mirror);
            ASSERT_EQ(from_mirror, from_world) << "viewer " << v << " tick " << tick;
            selected += from_world.size();
        }
    }
    EXPECT_GT(selected, 0u);
    EXPECT_LT(selected, 90u * players.size() * (world.entity_count() - 1)); // some are culled
    EXPECT_GT(world.frags(), 0u);    // shots killed, so deaths and respawns were mirrored
    EXPECT_GT(pending_respawns, 0u); // and pending ones travelled
}

TEST(WorldTick, AMirrorIsReadNotStepped) {
    const auto map = testing::rooms_map();
    GameWorld world(busy_settings(), map);
    GameWorld mirror(busy_settings(), map);
    world.step(1.0f / 30.0f);
    auto decoded = decode_world_tick(tick_bytes(world, 1), "test");
    ASSERT_TRUE(decoded.ok());
    apply_world_tick(std::move(decoded).value(), mirror);
    EXPECT_TRUE(mirror.mirrored());
    EXPECT_THROW(mirror.step(1.0f / 30.0f), std::logic_error);
    std::vector<Entity> out_of_order = world.entities();
    std::swap(out_of_order[0], out_of_order[1]);
    EXPECT_THROW(mirror.mirror(out_of_order, 0, world.next_id()), std::invalid_argument);
    EXPECT_EQ(mirror.entity_count(), world.entity_count()); // unchanged by the refusal
}

class BadWorldTick : public ::testing::Test {
protected:
    void SetUp() override {
        world_ = std::make_unique<GameWorld>(busy_settings(), testing::rooms_map());
        world_->spawn_player();
        world_->step(1.0f / 30.0f);
        good_ = tick_bytes(*world_, 1);
    }
    /// The reason decode_world_tick gives for `bytes`, or "" when it accepts them.
    static std::string why(const std::vector<std::byte>& bytes,
                           std::optional<std::uint64_t> key = std::nullopt) {
        auto decoded = decode_world_tick(bytes, "nats:dsoc.world.tick", key);
        return decoded.ok() ? "" : decoded.error().message();
    }
    template <typename T>
    std::vector<std::byte> with(std::size_t offset, T value) const {
        std::vector<std::byte> bytes = good_;
        std::memcpy(bytes.data() + offset, &value, sizeof value);
        return bytes;
    }
    std::unique_ptr<GameWorld> world_;
    std::vector<std::byte> good_;
};

constexpr std::size_t kFirstEntity = 56; // the header's size (docs/scale-out.md)

TEST_F(BadWorldTick, EveryTruncationIsRefused) {
    ASSERT_EQ(why(good_), "");
    for (std::size_t n = 0; n < good_.size(); ++n) {
        const std::vector<std::byte> cut(good_.begin(), good_.begin() + static_cast<long>(n));
        EXPECT_NE(why(cut), "") << n << " bytes";
    }
    std::vector<std::byte> longer = good_;
    longer.push_back(std::byte{0});
    EXPECT_NE(why(longer).find("after the last entity"), std::string::npos) << why(longer);
}

TEST_F(BadWorldTick, EachBadFieldIsNamed) {
    EXPECT_NE(why(with<std::uint32_t>(0, 0x12345678u)).find("magic"), std::string::npos);
    EXPECT_NE(why(with<std::uint16_t>(4, 9)).find("version 9"), std::string::npos);
    EXPECT_NE(why(good_, 43).find("another world"), std::string::npos);
    EXPECT_NE(why(with<std::uint64_t>(16, 0)).find("instance 0"), std::string::npos);
    EXPECT_NE(why(with<std::uint32_t>(52, 0xffffffffu)).find("do not fit"), std::string::npos);
    // The first entity's fields (its layout: docs/scale-out.md).
    EXPECT_NE(why(with<std::uint32_t>(kFirstEntity, 0)).find("entity 0"), std::string::npos);
    EXPECT_NE(why(with<std::uint8_t>(kFirstEntity + 4, 7)).find("unknown kind 7"),
              std::string::npos);
    EXPECT_NE(why(with<std::uint8_t>(kFirstEntity + 5, 0x80)).find("unknown flags"),
              std::string::npos);
    EXPECT_NE(why(with<std::int32_t>(kFirstEntity + 8, 1000)).find("health 1000"),
              std::string::npos);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(why(with<float>(kFirstEntity + 12, nan)).find("position"), std::string::npos);
    EXPECT_NE(why(with<float>(kFirstEntity + 24, 1.0e9f)).find("velocity"), std::string::npos);
    EXPECT_NE(why(with<float>(kFirstEntity + 52, 500.0f)).find("view angles"), std::string::npos);
    EXPECT_NE(why(with<float>(kFirstEntity + 60, -1.0f)).find("sound"), std::string::npos);
    // A respawn flag on an entity whose bytes hold none runs into the next entity's,
    // or off the end: either way refused.
    EXPECT_NE(why(with<std::uint8_t>(kFirstEntity + 5, 8)), "");
    // Ids must increase: the second entity given the first's id.
    std::uint32_t first_id = 0;
    std::memcpy(&first_id, good_.data() + kFirstEntity, sizeof first_id);
    EXPECT_NE(why(with<std::uint32_t>(kFirstEntity + 68, first_id)).find("ids increase"),
              std::string::npos);
}

} // namespace
} // namespace dsoc::scaleout
