// The world process over a real nats-server (skipped, with the reason, where the
// binary is absent): a gateway reserves ids, and a joined one appears at the next
// tick; its inputs move that player and no other; a leave removes it; a join or leave
// sent again changes nothing; a gateway lost past its timeout gets its players back by
// re-joining them, and its ids are released once others need the room; messages naming
// another world instance take nothing and keep no gateway alive; bad messages and
// inputs for entities that are not joined players are counted, and the world carries
// on publishing ticks a gateway can mirror.

#include "dsoc/scaleout/world_process.hpp"
#include "dsoc/scaleout/world_tick.hpp"
#include "support/eventually.hpp"
#include "support/nats_server.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <limits>
#include <mutex>
#include <thread>

namespace dsoc::scaleout {
namespace {

using namespace std::chrono_literals;
using testing::eventually;

constexpr std::uint64_t kGateway = 0x6a7e;

class WorldProcessTest : public ::testing::Test {
protected:
    void SetUp() override {
        if (testing::nats_server_binary().empty()) {
            GTEST_SKIP() << testing::kNoNatsServer;
        }
        server_ = std::make_unique<testing::NatsServer>();
        NatsLinkOptions o;
        o.url = server_->url();
        world_link_ = std::make_unique<NatsLink>(o);
        gateway_link_ = std::make_unique<NatsLink>(o);
        settings_.bots = 10;
        process_ = std::make_unique<WorldProcess>(testing::rooms_map(), settings_, 30, *world_link_,
                                                  "t", gateway_timeout());
        ticks_ = gateway_link_->subscribe(world_subject("t", "tick"), [this](const NatsMessage& m) {
            auto tick = decode_world_tick(m.data, std::string(m.subject), process_->world_key());
            ASSERT_TRUE(tick.ok()) << tick.error().message();
            const std::lock_guard lock(mutex_);
            newest_ = std::move(tick).value();
        });
        ASSERT_TRUE(world_link_->flush(2000ms));
        ASSERT_TRUE(gateway_link_->flush(2000ms));
    }
    [[nodiscard]] virtual std::chrono::milliseconds gateway_timeout() const {
        return WorldProcess::kDefaultGatewayTimeout;
    }
    /// Gateway `id`, following this world's instance.
    [[nodiscard]] BatchFrom from(std::uint64_t id) const { return {id, process_->instance()}; }
    /// Gateway `id`'s heartbeat: an empty input batch.
    void beat(std::uint64_t id) {
        std::vector<std::byte> bytes;
        encode_inputs(from(id), {}, bytes);
        send("gateway", bytes);
    }
    void TearDown() override {
        ticks_.reset();
        process_.reset();
    }
    /// Publishes `bytes` on the world's `what` subject and waits until it arrived.
    void send(const std::string& what, const std::vector<std::byte>& bytes) {
        const std::uint64_t before = process_->messages_received();
        ASSERT_TRUE(gateway_link_->publish(world_subject("t", what), bytes));
        ASSERT_TRUE(eventually([&] { return process_->messages_received() > before; }));
    }
    /// A block of `count` ids reserved for `gateway`.
    IdBlock reserve(std::uint64_t gateway, std::uint32_t count) {
        std::vector<std::byte> bytes;
        encode_reserve_request({gateway, process_->instance(), count}, bytes);
        const auto answer = gateway_link_->request(world_subject("t", "reserve"), bytes, 2000ms);
        if (!answer) {
            ADD_FAILURE() << "no answer to a reserve request";
            return {};
        }
        auto block = decode_id_block(*answer, "reserve");
        EXPECT_TRUE(block.ok()) << block.error().message();
        return block.ok() ? block.value() : IdBlock{};
    }
    /// Gateway `gateway`'s joins (leaves) of `ids`, waited for.
    void send_ids(IdBatchKind kind, std::uint64_t gateway, std::vector<std::uint32_t> ids) {
        std::vector<std::byte> bytes;
        encode_id_batch(kind, from(gateway), ids, bytes);
        send("gateway", bytes);
    }
    /// Runs one tick and waits for it to reach the gateway.
    WorldTick tick() {
        process_->tick();
        const std::uint64_t want = process_->stats().ticks;
        EXPECT_TRUE(eventually([&] {
            const std::lock_guard lock(mutex_);
            return newest_.tick == want;
        }));
        const std::lock_guard lock(mutex_);
        return newest_;
    }
    static const interest::Entity* find(const WorldTick& tick, std::uint32_t id) {
        for (const interest::Entity& e : tick.entities) {
            if (e.id == id) {
                return &e;
            }
        }
        return nullptr;
    }

    std::unique_ptr<testing::NatsServer> server_;
    std::unique_ptr<NatsLink> world_link_;
    std::unique_ptr<NatsLink> gateway_link_;
    interest::WorldSettings settings_;
    std::unique_ptr<WorldProcess> process_;
    std::unique_ptr<NatsSubscription> ticks_;
    std::mutex mutex_;
    WorldTick newest_;
};

TEST_F(WorldProcessTest, AJoinedPlayerMovesByItsInputsAndLeaves) {
    const WorldTick first = tick();
    EXPECT_EQ(first.entities.size(), 10u); // the bots

    std::vector<std::byte> bytes;
    encode_reserve_request({kGateway, first.instance, 3}, bytes); // the instance followed
    const auto answer = gateway_link_->request(world_subject("t", "reserve"), bytes, 2000ms);
    ASSERT_TRUE(answer.has_value());
    auto block = decode_id_block(*answer, "reserve");
    ASSERT_TRUE(block.ok()) << block.error().message();
    EXPECT_EQ(block->world_key, process_->world_key());
    EXPECT_EQ(block->instance, process_->instance());
    EXPECT_EQ(first.instance, process_->instance());
    EXPECT_EQ(block->count, 3u);
    const std::uint32_t player = block->first_id + 1;
    EXPECT_EQ(find(first, player), nullptr);
    EXPECT_EQ(find(tick(), player), nullptr); // reserved is not joined

    const std::uint32_t joins[] = {player, 999'999}; // the second was never reserved
    encode_id_batch(IdBatchKind::join, from(kGateway), joins, bytes);
    send("gateway", bytes);
    EXPECT_EQ(process_->stats().for_strangers, 1u);
    const WorldTick joined = tick();
    const interest::Entity* spawned = find(joined, player);
    ASSERT_NE(spawned, nullptr);
    EXPECT_EQ(spawned->kind, interest::EntityKind::player);
    const glm::vec3 start = spawned->move.position;

    const PlayerInput forward{player, glm::vec3(1.0f, 0.0f, 0.0f), false, false, 0.0f, 0.0f};
    encode_inputs(from(kGateway), std::span(&forward, 1), bytes);
    send("gateway", bytes);
    WorldTick moved;
    for (int i = 0; i < 15; ++i) {
        moved = tick();
    }
    const interest::Entity* after = find(moved, player);
    ASSERT_NE(after, nullptr);
    EXPECT_GT(glm::length(after->move.position - start), 20.0f); // half a second's walk

    // An input for a bot is not the gateway's to give: counted, the bot left alone.
    const PlayerInput steal{
        first.entities[0].id, glm::vec3(0.0f, 1.0f, 0.0f), true, true, 0.0f, 0.0f};
    encode_inputs(from(kGateway), std::span(&steal, 1), bytes);
    send("gateway", bytes);
    EXPECT_EQ(process_->stats().for_strangers, 2u);

    const std::uint32_t ids[] = {player};
    encode_id_batch(IdBatchKind::leave, from(kGateway), ids, bytes);
    send("gateway", bytes);
    const WorldTick left = tick();
    EXPECT_EQ(find(left, player), nullptr);
    EXPECT_EQ(process_->stats().joins, 1u);
    EXPECT_EQ(process_->stats().leaves, 1u);
    EXPECT_EQ(process_->stats().inputs, 1u);
}

class ShortGatewayTimeout : public WorldProcessTest {
protected:
    [[nodiscard]] std::chrono::milliseconds gateway_timeout() const override { return 500ms; }
};

TEST_F(ShortGatewayTimeout, APlayerBelongsToItsGatewayAndLeavesWithIt) {
    const std::uint32_t mine = reserve(kGateway, 1).first_id;
    const std::uint32_t theirs = reserve(kGateway + 1, 1).first_id;
    // An id reserved for one gateway is not another's to join.
    send_ids(IdBatchKind::join, kGateway + 1, {mine});
    EXPECT_EQ(process_->stats().for_strangers, 1u);
    send_ids(IdBatchKind::join, kGateway, {mine});
    send_ids(IdBatchKind::join, kGateway + 1, {theirs});
    ASSERT_NE(find(tick(), mine), nullptr);

    // Another gateway can neither steer nor remove this gateway's player.
    std::vector<std::byte> bytes;
    const PlayerInput steer{mine, glm::vec3(1.0f, 0.0f, 0.0f), false, false, 0.0f, 0.0f};
    encode_inputs(from(kGateway + 1), std::span(&steer, 1), bytes);
    send("gateway", bytes);
    send_ids(IdBatchKind::leave, kGateway + 1, {mine});
    EXPECT_EQ(process_->stats().for_strangers, 3u);
    beat(kGateway);
    EXPECT_NE(find(tick(), mine), nullptr);

    // Only the second gateway keeps sending (its heartbeat): past the timeout the first
    // one's player is removed, the second one's stays.
    const auto silent_since = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - silent_since < 800ms) {
        beat(kGateway + 1);
        std::this_thread::sleep_for(50ms);
    }
    const WorldTick after = tick();
    EXPECT_EQ(find(after, mine), nullptr);
    EXPECT_NE(find(after, theirs), nullptr);
    EXPECT_EQ(process_->stats().gateways_lost, 1u);
}

TEST_F(WorldProcessTest, ARepeatedJoinOrLeaveChangesNothing) {
    const std::uint32_t id = reserve(kGateway, 1).first_id;
    send_ids(IdBatchKind::join, kGateway, {id});
    send_ids(IdBatchKind::join, kGateway, {id}); // a re-send that crossed the first
    const WorldTick joined = tick();
    ASSERT_NE(find(joined, id), nullptr);
    EXPECT_EQ(joined.entities.size(), 11u);      // the bots, and the player once
    send_ids(IdBatchKind::join, kGateway, {id}); // and one after its spawn
    EXPECT_EQ(tick().entities.size(), 11u);

    send_ids(IdBatchKind::leave, kGateway, {id});
    send_ids(IdBatchKind::leave, kGateway, {id}); // before the step that removes it
    EXPECT_EQ(find(tick(), id), nullptr);
    send_ids(IdBatchKind::leave, kGateway, {id}); // and after
    send_ids(IdBatchKind::join, kGateway, {id});  // a left player does not come back
    EXPECT_EQ(find(tick(), id), nullptr);
    const WorldProcessStats stats = process_->stats();
    EXPECT_EQ(stats.joins, 1u);
    EXPECT_EQ(stats.leaves, 1u);
    EXPECT_EQ(stats.repeated, 4u);
    EXPECT_EQ(stats.for_strangers, 1u); // the join after its leave
}

TEST_F(ShortGatewayTimeout, ALostGatewayThatComesBackGetsItsPlayersBack) {
    const IdBlock block = reserve(kGateway, 3);
    const std::uint32_t stays = block.first_id;
    const std::uint32_t leaves = block.first_id + 1;
    send_ids(IdBatchKind::join, kGateway, {stays, leaves});
    ASSERT_NE(find(tick(), stays), nullptr);

    // Cut off past the timeout: its players are removed.
    std::this_thread::sleep_for(700ms);
    const WorldTick lost = tick();
    EXPECT_EQ(find(lost, stays), nullptr);
    EXPECT_EQ(find(lost, leaves), nullptr);
    EXPECT_EQ(process_->stats().gateways_lost, 1u);

    // Back: what it sent while cut off (one client left; the other's input, before its
    // re-join) and then the re-join of the players it still has.
    send_ids(IdBatchKind::leave, kGateway, {leaves});
    const PlayerInput early{stays, glm::vec3(1.0f, 0.0f, 0.0f), false, false, 0.0f, 0.0f};
    std::vector<std::byte> bytes;
    encode_inputs(from(kGateway), std::span(&early, 1), bytes);
    send("gateway", bytes);
    send_ids(IdBatchKind::join, kGateway, {stays});
    send_ids(IdBatchKind::join, kGateway, {leaves}); // left: its id was released
    const WorldTick back = tick();
    EXPECT_NE(find(back, stays), nullptr);
    EXPECT_EQ(find(back, leaves), nullptr);
    const WorldProcessStats stats = process_->stats();
    EXPECT_EQ(stats.gateways_back, 1u);
    EXPECT_EQ(stats.joins, 3u);         // two, and one again
    EXPECT_EQ(stats.for_strangers, 1u); // the released id's join; not the early input
}

TEST_F(ShortGatewayTimeout, LostGatewaysAreForgottenWhenTheirIdsAreNeeded) {
    for (std::size_t reserved = 0; reserved < WorldProcess::kMaxReserved; reserved += kMaxIdBlock) {
        ASSERT_EQ(reserve(kGateway, kMaxIdBlock).count, kMaxIdBlock);
    }
    // Full: another gateway's request is refused while the first is alive...
    std::vector<std::byte> bytes;
    encode_reserve_request({kGateway + 1, process_->instance(), 1}, bytes);
    EXPECT_FALSE(gateway_link_->request(world_subject("t", "reserve"), bytes, 300ms).has_value());
    EXPECT_NE(process_->stats().last_error.find("reserved and not joined"), std::string::npos)
        << process_->stats().last_error;
    // ...and answered once it was lost, its ids released.
    std::this_thread::sleep_for(700ms);
    beat(kGateway + 1);
    (void)tick();
    EXPECT_EQ(process_->stats().gateways_lost, 1u);
    EXPECT_EQ(reserve(kGateway + 1, 1).count, 1u);
    EXPECT_EQ(process_->stats().gateways_forgotten, 1u);
}

TEST_F(ShortGatewayTimeout, MessagesNamingAnotherInstanceTakeNothingAndKeepNoGatewayAlive) {
    // What a gateway that follows another world process on this name sends.
    const std::uint32_t id = reserve(kGateway, 2).first_id;
    send_ids(IdBatchKind::join, kGateway, {id});
    ASSERT_NE(find(tick(), id), nullptr);
    const BatchFrom other{kGateway, process_->instance() ^ 1};
    std::vector<std::byte> bytes;
    encode_reserve_request({kGateway, other.instance, 8}, bytes);
    EXPECT_FALSE(gateway_link_->request(world_subject("t", "reserve"), bytes, 300ms).has_value());
    const std::uint32_t spare = id + 1; // reserved for it, not joined
    encode_id_batch(IdBatchKind::join, other, std::span(&spare, 1), bytes);
    send("gateway", bytes);
    const PlayerInput steer{id, glm::vec3(1.0f, 0.0f, 0.0f), true, true, 0.0f, 0.0f};
    encode_inputs(other, std::span(&steer, 1), bytes);
    send("gateway", bytes);
    encode_id_batch(IdBatchKind::leave, other, std::span(&id, 1), bytes);
    send("gateway", bytes);
    const WorldTick after = tick();
    EXPECT_NE(find(after, id), nullptr);
    EXPECT_EQ(find(after, spare), nullptr);
    WorldProcessStats stats = process_->stats();
    EXPECT_EQ(stats.other_instance, 4u);
    EXPECT_EQ(stats.ids_reserved, 2u);
    EXPECT_EQ(stats.joins, 1u);
    EXPECT_EQ(stats.leaves, 0u);
    EXPECT_EQ(stats.inputs, 0u);
    EXPECT_EQ(stats.for_strangers, 0u);
    EXPECT_EQ(stats.bad_messages, 0u);

    // Its heartbeats keep no gateway alive here: past the timeout its player goes.
    const auto since = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - since < 800ms) {
        encode_inputs(other, {}, bytes);
        send("gateway", bytes);
        std::this_thread::sleep_for(50ms);
    }
    EXPECT_EQ(find(tick(), id), nullptr);
    stats = process_->stats();
    EXPECT_EQ(stats.gateways_lost, 1u);
    EXPECT_GT(stats.other_instance, 4u);
}

TEST_F(WorldProcessTest, BadMessagesAreCountedAndTheWorldCarriesOn) {
    const std::vector<std::byte> garbage(30, std::byte{0x41});
    send("gateway", garbage); // no magic of ours
    std::vector<std::byte> bad_input;
    encode_inputs(from(0), {}, bad_input); // gateway id 0
    send("gateway", bad_input);
    std::vector<std::byte> bad_leave;
    encode_id_batch(IdBatchKind::leave, from(kGateway), {}, bad_leave);
    bad_leave.pop_back(); // truncated
    send("gateway", bad_leave);
    send("reserve", garbage);
    const WorldProcessStats stats = process_->stats();
    EXPECT_EQ(stats.bad_messages, 4u);
    EXPECT_NE(stats.last_error.find("dsoc.t.reserve"), std::string::npos) << stats.last_error;
    const WorldTick after = tick();
    EXPECT_EQ(after.tick, 1u);
    EXPECT_EQ(after.entities.size(), 10u);
}

TEST(WorldMessages, EachDecoderRefusesWhatItsEncoderCouldNotHaveWritten) {
    constexpr std::uint64_t kInstance = 0x1457;
    constexpr BatchFrom kFrom{kGateway, kInstance};
    std::vector<std::byte> bytes;
    const PlayerInput in{7, glm::vec3(0.5f, -1.0f, 0.0f), true, true, 90.0f, -10.0f};
    encode_inputs(kFrom, std::span(&in, 1), bytes);
    auto decoded = decode_inputs(bytes, "s");
    ASSERT_TRUE(decoded.ok());
    EXPECT_EQ(decoded->gateway, kGateway);
    EXPECT_EQ(decoded->instance, kInstance);
    ASSERT_EQ(decoded->entries.size(), 1u);
    EXPECT_EQ(decoded->entries[0].entity_id, 7u);
    EXPECT_TRUE(decoded->entries[0].jump && decoded->entries[0].fire);
    EXPECT_EQ(decoded->entries[0].wish, glm::vec3(0.5f, -1.0f, 0.0f));
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        EXPECT_FALSE(decode_inputs(std::span(bytes).first(n), "s").ok()) << n;
    }
    constexpr std::size_t kHeader = 28; // magic, version, 0, gateway, instance, count
    std::vector<std::byte> nan = bytes;
    const float bad = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan.data() + kHeader + 12, &bad, sizeof bad); // the yaw
    EXPECT_NE(decode_inputs(nan, "s").error().message().find("input 0"), std::string::npos);
    std::vector<std::byte> far = bytes;
    const float two = 2.0f;
    std::memcpy(far.data() + kHeader + 4, &two, sizeof two); // wish x
    EXPECT_FALSE(decode_inputs(far, "s").ok());
    encode_inputs({0, kInstance}, std::span(&in, 1), bytes);
    EXPECT_NE(decode_inputs(bytes, "s").error().message().find("gateway id 0"), std::string::npos);
    encode_inputs({kGateway, 0}, std::span(&in, 1), bytes);
    EXPECT_NE(decode_inputs(bytes, "s").error().message().find("world instance 0"),
              std::string::npos);

    const std::uint32_t ids[] = {3, 0};
    encode_id_batch(IdBatchKind::leave, kFrom, ids, bytes);
    EXPECT_NE(decode_id_batch(IdBatchKind::leave, bytes, "s").error().message().find("entry 1"),
              std::string::npos);
    EXPECT_FALSE(decode_id_batch(IdBatchKind::join, bytes, "s").ok()); // a leave is no join
    encode_id_batch(IdBatchKind::join, kFrom, std::span(ids, 1), bytes);
    EXPECT_EQ(decode_id_batch(IdBatchKind::join, bytes, "s")->instance, kInstance);
    encode_id_batch(IdBatchKind::join, {kGateway, 0}, std::span(ids, 1), bytes);
    EXPECT_FALSE(decode_id_batch(IdBatchKind::join, bytes, "s").ok()); // instance 0
    encode_id_block({1, 7, 0, 5}, bytes);
    EXPECT_FALSE(decode_id_block(bytes, "s").ok()); // id 0
    encode_id_block({1, 7, 9, 5000}, bytes);
    EXPECT_FALSE(decode_id_block(bytes, "s").ok()); // over kMaxIdBlock
    encode_id_block({1, 0, 9, 5}, bytes);
    EXPECT_FALSE(decode_id_block(bytes, "s").ok()); // instance 0
    encode_id_block({1, 7, 9, 5}, bytes);
    EXPECT_EQ(decode_id_block(bytes, "s")->first_id, 9u);
    EXPECT_EQ(decode_id_block(bytes, "s")->instance, 7u);
    EXPECT_FALSE(decode_reserve_request(bytes, "s").ok()); // a block is no request
    encode_reserve_request({kGateway, kInstance, 0}, bytes);
    EXPECT_FALSE(decode_reserve_request(bytes, "s").ok());
    encode_reserve_request({0, kInstance, 64}, bytes);
    EXPECT_FALSE(decode_reserve_request(bytes, "s").ok()); // gateway 0
    encode_reserve_request({kGateway, kInstance, 64}, bytes);
    EXPECT_EQ(decode_reserve_request(bytes, "s")->count, 64u);
    EXPECT_EQ(decode_reserve_request(bytes, "s")->gateway, kGateway);
    EXPECT_EQ(decode_reserve_request(bytes, "s")->instance, kInstance);
    // None naming no instance: two world processes on one name would both answer it.
    encode_reserve_request({kGateway, 0, 64}, bytes);
    const auto no_instance = decode_reserve_request(bytes, "dsoc.w.reserve");
    ASSERT_FALSE(no_instance.ok());
    EXPECT_NE(no_instance.error().message().find("dsoc.w.reserve"), std::string::npos);
    EXPECT_NE(no_instance.error().message().find("world instance 0"), std::string::npos)
        << no_instance.error().message();
}

} // namespace
} // namespace dsoc::scaleout
