#include "dsoc/server/world_feed.hpp"

#include "dsoc/scaleout/world_process.hpp"

#include <boost/asio/post.hpp>
#include <spdlog/spdlog.h>

#include <random>

namespace dsoc::server {

namespace {

/// Ids asked for at a time: a second's joins of a busy gateway.
constexpr std::uint32_t kIdBlock = 256;
/// How often an unanswered reserve is asked again.
constexpr auto kReserveRetry = std::chrono::seconds(1);

/// A gateway's id for the world's bookkeeping: random, never 0.
std::uint64_t random_gateway_id() {
    std::random_device device;
    std::uint64_t id = 0;
    while (id == 0) {
        id = (static_cast<std::uint64_t>(device()) << 32) ^ device();
    }
    return id;
}

} // namespace

WorldFeed::WorldFeed(boost::asio::io_context& io, const ServerConfig& config,
                     std::uint64_t world_key, std::function<void()> on_tick,
                     std::function<void()> wake)
    : io_(io), world_name_(config.world_name), world_key_(world_key),
      gateway_id_(random_gateway_id()), on_tick_(std::move(on_tick)), wake_(std::move(wake)) {
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

void WorldFeed::on_tick_message(const scaleout::NatsMessage& message) {
    auto tick = scaleout::decode_world_tick(message.data, std::string(message.subject), world_key_);
    {
        const std::lock_guard lock(mutex_);
        if (!tick.ok()) {
            ++stats_.bad_messages;
            stats_.last_error = tick.error().message();
            return;
        }
        if (tick->tick <= last_tick_) {
            ++stats_.bad_messages; // not newer: a restarted world, or a second one
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
    for (std::uint32_t i = 0; i < block->count; ++i) {
        ids_.push_back(block->first_id + i);
    }
    ++stats_.id_blocks;
}

std::optional<scaleout::WorldTick> WorldFeed::take_newest() {
    const std::lock_guard lock(mutex_);
    std::optional<scaleout::WorldTick> out = std::move(newest_);
    newest_.reset();
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
        if (!ids_.empty()) {
            id = ids_.front();
            ids_.pop_front();
        }
    }
    maybe_reserve();
    return id;
}

void WorldFeed::maybe_reserve() {
    const auto now = std::chrono::steady_clock::now();
    {
        const std::lock_guard lock(mutex_);
        if (ids_.size() >= kIdBlock / 2 ||
            (reserve_pending_ && now - last_reserve_ < kReserveRetry)) {
            return;
        }
        reserve_pending_ = true;
        last_reserve_ = now;
    }
    std::vector<std::byte> bytes;
    scaleout::encode_reserve_request(kIdBlock, bytes);
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

void WorldFeed::send_joins(std::span<const std::uint32_t> entity_ids) {
    if (!entity_ids.empty()) {
        scaleout::encode_id_batch(scaleout::IdBatchKind::join, gateway_id_, entity_ids, bytes_);
        send("gateway", bytes_);
    }
}

void WorldFeed::send_inputs(std::span<const scaleout::PlayerInput> inputs) {
    // Empty or not: the world takes it as this gateway's heartbeat.
    scaleout::encode_inputs(gateway_id_, inputs, bytes_);
    send("gateway", bytes_);
    maybe_reserve(); // also retries an unanswered reserve, once a tick at most
}

void WorldFeed::send_leaves(std::span<const std::uint32_t> entity_ids) {
    if (!entity_ids.empty()) {
        scaleout::encode_id_batch(scaleout::IdBatchKind::leave, gateway_id_, entity_ids, bytes_);
        send("gateway", bytes_);
    }
}

WorldFeedStats WorldFeed::stats() const {
    const std::lock_guard lock(mutex_);
    WorldFeedStats s = stats_;
    s.ids_left = ids_.size();
    s.nats_disconnects = link_->disconnects();
    s.nats_reconnects = link_->reconnects();
    return s;
}

} // namespace dsoc::server
