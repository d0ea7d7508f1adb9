#include "dsoc/server/world_feed.hpp"

#include "dsoc/scaleout/world_process.hpp"

#include <boost/asio/post.hpp>
#include <spdlog/spdlog.h>

#include <utility>

namespace dsoc::server {

namespace {

/// Ids asked for at a time: a second's joins of a busy gateway.
constexpr std::uint32_t kIdBlock = 256;
/// How often an unanswered reserve is asked again.
constexpr auto kReserveRetry = std::chrono::seconds(1);

} // namespace

WorldFeed::WorldFeed(boost::asio::io_context& io, const ServerConfig& config,
                     std::uint64_t world_key, std::function<void()> on_tick,
                     std::function<void()> wake)
    : io_(io), world_name_(config.world_name), world_key_(world_key),
      gateway_id_(scaleout::random_id()), on_tick_(std::move(on_tick)), wake_(std::move(wake)) {
    scaleout::NatsLinkOptions options;
    options.url = config.nats_url;
    options.name = "dsoc-gateway:" + config.world_name;
    link_ = std::make_unique<scaleout::NatsLink>(options);
    inbox_ = scaleout::NatsLink::new_inbox();
    block_sub_ =
        link_->subscribe(inbox_, [this](const scaleout::NatsMessage& m) { on_block_message(m); });
    // A gateway that falls behind keeps the newest few ticks, not an unbounded queue.
    tick_sub_ = link_->subscribe(
        scaleout::world_subject(world_name_, "tick"),
        [this](const scaleout::NatsMessage& m) { on_tick_message(m); }, 4);
    maybe_reserve();
}

WorldFeed::~WorldFeed() {
    tick_sub_.reset(); // no callback after these
    block_sub_.reset();
}

bool WorldFeed::follow(std::uint64_t instance) {
    const auto now = std::chrono::steady_clock::now();
    if (instance == instance_) {
        heard_ = now;
        return true;
    }
    if (instance_ != 0 && now - heard_ < kWorldSilence) {
        ++stats_.other_instance; // the followed world is live: a second one, or a stray
        return false;
    }
    if (instance_ != 0) { // the world process restarted
        restart_ = WorldRestart{restart_ ? restart_->old_instance : instance_, instance};
        ++stats_.world_restarts;
    }
    instance_ = instance;
    heard_ = now;
    last_tick_ = 0; // its ticks count from 1
    stats_.ticks_skipped += newest_ ? 1 : 0;
    newest_.reset(); // the old world's
    ids_.clear();
    reserve_pending_ = false; // an answer from the old world would be refused: ask anew
    return true;
}

void WorldFeed::on_tick_message(const scaleout::NatsMessage& message) {
    auto tick = scaleout::decode_world_tick(message.data, std::string(message.subject), world_key_);
    {
        const std::lock_guard lock(mutex_);
        if (!tick.ok()) {
            ++stats_.bad_messages;
            stats_.last_error = tick.error().message();
            return;
        }
        if (!follow(tick->instance)) {
            return;
        }
        if (tick->tick <= last_tick_) {
            ++stats_.bad_messages; // not newer: a second world of the same instance?
            stats_.last_error =
                "world tick " + std::to_string(tick->tick) + " after " + std::to_string(last_tick_);
            return;
        }
        stats_.ticks_skipped += newest_ ? 1 : 0;
        ++stats_.ticks_received;
        last_tick_ = tick->tick;
        newest_ = std::move(tick).value();
    }
    boost::asio::post(io_, [this] { on_tick_(); });
    if (wake_) {
        wake_();
    }
}

void WorldFeed::on_block_message(const scaleout::NatsMessage& message) {
    auto block = scaleout::decode_id_block(message.data, std::string(message.subject));
    const std::lock_guard lock(mutex_);
    reserve_pending_ = false;
    if (!block.ok() || block->world_key != world_key_) {
        ++stats_.bad_messages;
        stats_.last_error = block.ok() ? "an id block of another world" : block.error().message();
        return;
    }
    if (!follow(block->instance)) {
        return;
    }
    ids_.add_block(block->first_id, block->count);
    ++stats_.id_blocks;
}

std::optional<TakenTick> WorldFeed::take_newest() {
    std::optional<TakenTick> out;
    GatewayIds::Resend resend;
    {
        const std::lock_guard lock(mutex_);
        if (!newest_) {
            return out;
        }
        out.emplace(TakenTick{std::move(*newest_), std::exchange(restart_, std::nullopt)});
        newest_.reset();
        resend = ids_.check(out->tick.entities, GatewayIds::Clock::now());
        stats_.joins_resent += resend.joins.size();
        stats_.leaves_resent += resend.leaves.size();
    }
    send_batch(scaleout::IdBatchKind::join, resend.joins);
    send_batch(scaleout::IdBatchKind::leave, resend.leaves);
    return out;
}

bool WorldFeed::tick_waiting() const {
    const std::lock_guard lock(mutex_);
    return newest_.has_value();
}

std::uint32_t WorldFeed::take_entity_id() {
    std::uint32_t id = 0;
    {
        const std::lock_guard lock(mutex_);
        if (!restart_) { // else the server still holds sessions of the old world
            id = ids_.take();
        }
    }
    maybe_reserve();
    return id;
}

void WorldFeed::maybe_reserve() {
    const auto now = std::chrono::steady_clock::now();
    {
        const std::lock_guard lock(mutex_);
        if (ids_.left() >= kIdBlock / 2 ||
            (reserve_pending_ && now - last_reserve_ < kReserveRetry)) {
            return;
        }
        reserve_pending_ = true;
        last_reserve_ = now;
    }
    std::vector<std::byte> bytes;
    scaleout::encode_reserve_request({gateway_id_, kIdBlock}, bytes);
    if (!link_->publish_request(scaleout::world_subject(world_name_, "reserve"), inbox_, bytes)) {
        const std::lock_guard lock(mutex_);
        ++stats_.not_sent;
    }
}

void WorldFeed::send(const std::string& what, const std::vector<std::byte>& bytes) {
    if (!link_->publish(scaleout::world_subject(world_name_, what), bytes)) {
        const std::lock_guard lock(mutex_);
        ++stats_.not_sent;
    }
}

void WorldFeed::send_batch(scaleout::IdBatchKind kind, std::span<const std::uint32_t> entity_ids) {
    if (!entity_ids.empty()) {
        scaleout::encode_id_batch(kind, gateway_id_, entity_ids, bytes_);
        send("gateway", bytes_);
    }
}

void WorldFeed::send_ids(scaleout::IdBatchKind kind, std::span<const std::uint32_t> entity_ids) {
    if (entity_ids.empty()) {
        return;
    }
    std::vector<std::uint32_t> given_out;
    {
        const std::lock_guard lock(mutex_);
        const auto now = GatewayIds::Clock::now();
        given_out = kind == scaleout::IdBatchKind::join ? ids_.join(entity_ids, now)
                                                        : ids_.leave(entity_ids, now);
    }
    send_batch(kind, given_out);
}

void WorldFeed::send_joins(std::span<const std::uint32_t> entity_ids) {
    send_ids(scaleout::IdBatchKind::join, entity_ids);
}

void WorldFeed::send_inputs(std::span<const scaleout::PlayerInput> inputs) {
    // Empty or not: the world takes it as this gateway's heartbeat.
    scaleout::encode_inputs(gateway_id_, inputs, bytes_);
    send("gateway", bytes_);
    maybe_reserve(); // also retries an unanswered reserve, once a tick at most
}

void WorldFeed::send_leaves(std::span<const std::uint32_t> entity_ids) {
    send_ids(scaleout::IdBatchKind::leave, entity_ids);
}

WorldFeedStats WorldFeed::stats() const {
    const std::lock_guard lock(mutex_);
    WorldFeedStats s = stats_;
    s.ids_left = ids_.left();
    s.nats_disconnects = link_->disconnects();
    s.nats_reconnects = link_->reconnects();
    return s;
}

} // namespace dsoc::server
