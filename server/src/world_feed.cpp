#include "dsoc/server/world_feed.hpp"

#include "dsoc/scaleout/world_process.hpp"

#include <boost/asio/post.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <utility>

namespace dsoc::server {

namespace {

/// How often an unanswered reserve is asked again.
constexpr auto kReserveRetry = std::chrono::seconds(1);
/// How often refused messages are logged at most (every one is counted).
constexpr auto kRefusalLogEvery = std::chrono::seconds(10);

/// Ticks a world can step in `ns` of its clock at most: kMaxTickRate a second, and a
/// second more (a late step runs at once). No overflow for any `ns`. [Units: ticks]
std::uint64_t steps_within(std::uint64_t ns) {
    constexpr auto rate = static_cast<std::uint64_t>(kMaxTickRate);
    return rate + ns / 1'000'000 * rate / 1000;
}

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
    // The first ids are asked for at the first tick: of the instance it names.
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
        reserve_pending_ = false; // an answer from the old world would be refused: ask anew
    } // else first contact: the first reserve request goes to this instance
    instance_ = instance;
    heard_ = now;
    last_tick_ = 0; // its ticks count from 1
    stats_.ticks_skipped += newest_ ? 1 : 0;
    newest_.reset(); // the old world's
    ids_.clear();    // its players are the demand for the first block of the new instance
    return true;
}

void WorldFeed::refuse(std::string why) {
    ++stats_.bad_messages;
    ++refused_unlogged_;
    const auto now = std::chrono::steady_clock::now();
    if (stats_.bad_messages == 1 || now - refusal_logged_ >= kRefusalLogEvery) {
        spdlog::warn("world feed: {} message(s) from NATS refused since the last warning; the "
                     "last: {}",
                     refused_unlogged_, why);
        refusal_logged_ = now;
        refused_unlogged_ = 0;
    }
    stats_.last_error = std::move(why);
}

bool WorldFeed::plausible_start(const scaleout::WorldTick& tick, const std::string& subject) {
    const bool first = tick.instance != instance_ || last_tick_ == 0;
    if (first && tick.tick > kMaxFirstTick) {
        refuse(fmt::format("{}: world tick {} as the first of instance {:016x} (at most 2^40)",
                           subject, tick.tick, tick.instance));
        return false;
    }
    return true;
}

std::optional<std::uint64_t> WorldFeed::number_of(const scaleout::WorldTick& tick,
                                                  const std::string& subject,
                                                  std::chrono::steady_clock::time_point now) {
    std::uint64_t ahead = tick.tick; // the first of its instance: counts from 1
    const auto since = std::chrono::duration_cast<std::chrono::nanoseconds>(now - accepted_at_);
    const bool resync = last_tick_ != 0 && tick.tick <= last_tick_;
    if (resync) {
        if (since < kWorldSilence || tick.tick > kMaxFirstTick) {
            refuse(fmt::format("{}: world tick {} after {} of instance {:016x}: not newer", subject,
                               tick.tick, last_tick_, tick.instance));
            return std::nullopt;
        }
        // Nothing of the instance taken for kWorldSilence, its ticks all behind the last
        // one taken: that one was forged. Ahead by as many steps as a world can make since.
        ahead = steps_within(static_cast<std::uint64_t>(since.count()));
    } else if (last_tick_ != 0) {
        ahead = tick.tick - last_tick_;
        const std::uint64_t world_ns =
            tick.published_ns > last_published_ ? tick.published_ns - last_published_ : 0;
        if (ahead > steps_within(world_ns)) {
            refuse(fmt::format("{}: world tick {} after {} of instance {:016x}: {} ticks ahead "
                               "in {:.3f} s of the world's clock (a world steps at most {} "
                               "times a second)",
                               subject, tick.tick, last_tick_, tick.instance, ahead,
                               static_cast<double>(world_ns) * 1e-9, kMaxTickRate));
            return std::nullopt;
        }
    }
    if (ahead > kMaxNumber - last_number_) {
        refuse(fmt::format("{}: world tick {} of instance {:016x}: this gateway's tick numbers "
                           "would pass 2^62 ({} now)",
                           subject, tick.tick, tick.instance, last_number_));
        return std::nullopt;
    }
    if (resync) {
        ++stats_.world_resyncs;
        spdlog::warn("world feed: world tick {} of instance {:016x} taken after {:.1f} s of its "
                     "ticks going back from tick {} (that one forged?): the instance followed "
                     "anew",
                     tick.tick, tick.instance, std::chrono::duration<double>(since).count(),
                     last_tick_);
    }
    return last_number_ + ahead;
}

void WorldFeed::on_tick_message(const scaleout::NatsMessage& message) {
    const std::string subject(message.subject);
    auto tick = scaleout::decode_world_tick(message.data, subject, world_key_);
    {
        const std::lock_guard lock(mutex_);
        if (!tick.ok()) {
            refuse(tick.error().message());
            return;
        }
        if (!plausible_start(tick.value(), subject) || !follow(tick->instance)) {
            return;
        }
        const auto now = std::chrono::steady_clock::now();
        const std::optional<std::uint64_t> number = number_of(tick.value(), subject, now);
        if (!number) {
            return;
        }
        stats_.ticks_skipped += newest_ ? 1 : 0;
        ++stats_.ticks_received;
        last_tick_ = tick->tick;
        last_published_ = tick->published_ns;
        accepted_at_ = now;
        last_number_ = *number;
        newest_number_ = *number;
        newest_ = std::move(tick).value();
    }
    boost::asio::post(io_, [this] { on_tick_(); });
    if (wake_) {
        wake_();
    }
    maybe_reserve(); // at once when this tick made the gateway follow a new instance
}

void WorldFeed::on_block_message(const scaleout::NatsMessage& message) {
    auto block = scaleout::decode_id_block(message.data, std::string(message.subject));
    {
        const std::lock_guard lock(mutex_);
        if (!block.ok() || block->world_key != world_key_) {
            refuse(block.ok() ? std::string(message.subject) + ": an id block of another world"
                              : block.error().message());
            return; // the request stays pending: asked again after kReserveRetry
        }
        if (block->instance != instance_) {
            // Asked of the instance followed before a switch to another (its answer came
            // late), or a stray: ids of one instance only (they mean nothing to another).
            ++stats_.other_instance;
            return;
        }
        heard_ = std::chrono::steady_clock::now();
        ids_.add_block(block->first_id, block->count);
        ++stats_.id_blocks;
        reserve_pending_ = false;
    }
    maybe_reserve(); // the demand may be larger than one block
}

std::optional<TakenTick> WorldFeed::take_newest() {
    std::optional<TakenTick> out;
    GatewayIds::Resend resend;
    {
        const std::lock_guard lock(mutex_);
        if (!newest_) {
            return out;
        }
        out.emplace(TakenTick{
            std::move(*newest_), newest_number_, std::exchange(restart_, std::nullopt), {}});
        newest_.reset();
        served_ = out->tick.instance;
        resend = ids_.check(out->tick.entities, GatewayIds::Clock::now());
        stats_.joins_resent += resend.joins.size();
        stats_.leaves_resent += resend.leaves.size() - resend.abandoned.size();
        stats_.joins_abandoned += resend.abandoned.size();
        stats_.ids_voided += resend.voided;
        out->abandoned = std::move(resend.abandoned);
    }
    send_batch(scaleout::IdBatchKind::join, resend.joins);
    send_batch(scaleout::IdBatchKind::leave, resend.leaves);
    if (!out->abandoned.empty()) {
        maybe_reserve(); // their clients come back, and void ids were dropped
    }
    return out;
}

bool WorldFeed::tick_waiting() const {
    const std::lock_guard lock(mutex_);
    return newest_.has_value();
}

std::uint32_t WorldFeed::take_entity_id(std::string* why_not) {
    std::uint32_t id = 0;
    {
        const std::lock_guard lock(mutex_);
        if (restart_) { // the server still holds sessions of the old world
            if (why_not != nullptr) {
                *why_not = "the world process restarted and this gateway is ending the old "
                           "world's sessions";
            }
        } else if (id = ids_.take(); id == 0 && why_not != nullptr) {
            *why_not = instance_ == 0
                           ? "this gateway has heard no world tick yet (is the world process "
                             "running, at " +
                                 link_->url() + "?)"
                           : "the world process has not reserved entity ids for this gateway "
                             "yet (asked; is it running, at " +
                                 link_->url() + "?)";
        }
    }
    maybe_reserve();
    return id;
}

void WorldFeed::maybe_reserve() {
    const auto now = std::chrono::steady_clock::now();
    scaleout::ReserveRequest request{gateway_id_, 0, 0};
    {
        const std::lock_guard lock(mutex_);
        request.instance = instance_;
        request.count = ids_.to_reserve();
        // None before a world instance is followed: a request naming none would be
        // answered by every world process on the name.
        if (request.instance == 0 || request.count == 0 ||
            (reserve_pending_ && now - last_reserve_ < kReserveRetry)) {
            return;
        }
        reserve_pending_ = true;
        last_reserve_ = now;
    }
    std::vector<std::byte> bytes;
    scaleout::encode_reserve_request(request, bytes);
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

scaleout::BatchFrom WorldFeed::batch_from() const {
    const std::lock_guard lock(mutex_);
    return {gateway_id_, served_};
}

void WorldFeed::send_batch(scaleout::IdBatchKind kind, std::span<const std::uint32_t> entity_ids) {
    const scaleout::BatchFrom from = batch_from();
    if (!entity_ids.empty() && from.instance != 0) {
        scaleout::encode_id_batch(kind, from, entity_ids, bytes_);
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
    // Empty or not: the world takes it as this gateway's heartbeat (none before a tick
    // was served: no world to beat for).
    if (const scaleout::BatchFrom from = batch_from(); from.instance != 0) {
        scaleout::encode_inputs(from, inputs, bytes_);
        send("gateway", bytes_);
    }
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
