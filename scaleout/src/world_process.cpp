#include "dsoc/scaleout/world_process.hpp"

#include "dsoc/scaleout/world_tick.hpp"

#include <algorithm>

namespace dsoc::scaleout {

std::string world_subject(const std::string& world, const std::string& what) {
    return "dsoc." + world + "." + what;
}

WorldProcess::WorldProcess(std::shared_ptr<const maps::Map> map,
                           const interest::WorldSettings& settings, int tick_rate, NatsLink& link,
                           std::string world_name, std::chrono::milliseconds gateway_timeout)
    : world_(settings, map), dt_(1.0f / static_cast<float>(tick_rate)), link_(link),
      name_(std::move(world_name)), key_(scaleout::world_key(*map, settings)),
      gateway_timeout_(gateway_timeout) {
    // messages_received() counts a message once its effects are in.
    reserve_sub_ = link_.subscribe(world_subject(name_, "reserve"), [this](const NatsMessage& m) {
        on_reserve(m);
        ++received_;
    });
    gateway_sub_ = link_.subscribe(world_subject(name_, "gateway"), [this](const NatsMessage& m) {
        on_gateway(m);
        ++received_;
    });
}

WorldProcess::~WorldProcess() {
    // No callback runs after these (NatsSubscription), so none touches a dead world.
    reserve_sub_.reset();
    gateway_sub_.reset();
}

void WorldProcess::refuse(const std::string& why) {
    ++stats_.bad_messages;
    stats_.last_error = why;
}

template <typename T>
bool WorldProcess::accepted(const maps::Result<T>& decoded) {
    if (!decoded.ok()) {
        refuse(decoded.error().message());
    }
    return decoded.ok();
}

void WorldProcess::on_reserve(const NatsMessage& message) {
    auto count = decode_reserve_request(message.data, std::string(message.subject));
    IdBlock block{key_, 0, 0};
    {
        const std::lock_guard lock(mutex_);
        if (!accepted(count)) {
            return;
        }
        if (message.reply.empty()) {
            refuse(std::string(message.subject) + ": a reserve request without a reply subject");
            return;
        }
        if (reserved_.size() + count.value() > kMaxReserved) {
            refuse(std::string(message.subject) + ": " + std::to_string(reserved_.size()) +
                   " ids reserved and not joined already (at most " + std::to_string(kMaxReserved) +
                   ")");
            return;
        }
        // tick() steps under the same lock, so no step sees half a block.
        block.count = count.value();
        block.first_id = world_.reserve_player();
        reserved_.insert(block.first_id);
        for (std::uint32_t i = 1; i < block.count; ++i) {
            reserved_.insert(world_.reserve_player()); // consecutive: reserve_player counts up
        }
        stats_.ids_reserved += block.count;
    }
    std::vector<std::byte> bytes;
    encode_id_block(block, bytes);
    (void)link_.publish(message.reply, bytes); // lost: the gateway asks again, ids stay unused
}

WorldProcess::Gateway& WorldProcess::heard_from(std::uint64_t id) {
    Gateway& gateway = gateways_[id];
    gateway.last_heard = std::chrono::steady_clock::now();
    return gateway;
}

bool WorldProcess::owns(std::uint64_t gateway, std::uint32_t id) {
    const auto owner = owner_.find(id);
    if (owner != owner_.end() && owner->second == gateway) {
        return true;
    }
    ++stats_.for_strangers; // a bot, a stranger, another gateway's or a player who left
    return false;
}

void WorldProcess::on_gateway(const NatsMessage& message) {
    switch (gateway_message_of(message.data).value_or(static_cast<GatewayMessage>(255))) {
    case GatewayMessage::join:
        on_join(message);
        break;
    case GatewayMessage::input:
        on_input(message);
        break;
    case GatewayMessage::leave:
        on_leave(message);
        break;
    default: {
        const std::lock_guard lock(mutex_);
        refuse(std::string(message.subject) + ": not a join, input or leave batch");
    }
    }
}

void WorldProcess::on_join(const NatsMessage& message) {
    auto batch = decode_id_batch(IdBatchKind::join, message.data, std::string(message.subject));
    const std::lock_guard lock(mutex_);
    if (!accepted(batch)) {
        return;
    }
    Gateway& gateway = heard_from(batch->gateway);
    for (const std::uint32_t id : batch->entries) {
        if (reserved_.erase(id) == 0) {
            ++stats_.for_strangers; // never reserved, or joined already
            continue;
        }
        joining_.push_back(id);
        owner_[id] = batch->gateway;
        gateway.players.insert(id);
        ++stats_.joins;
    }
}

void WorldProcess::on_input(const NatsMessage& message) {
    auto batch = decode_inputs(message.data, std::string(message.subject));
    const std::lock_guard lock(mutex_);
    if (!accepted(batch)) {
        return;
    }
    heard_from(batch->gateway);
    for (const PlayerInput& in : batch->entries) {
        if (owns(batch->gateway, in.entity_id)) {
            PlayerInput& newest = inputs_[in.entity_id];
            const bool fired = newest.fire; // a shot is never lost to a newer input
            newest = in;
            newest.fire = newest.fire || fired;
        }
    }
}

void WorldProcess::on_leave(const NatsMessage& message) {
    auto batch = decode_id_batch(IdBatchKind::leave, message.data, std::string(message.subject));
    const std::lock_guard lock(mutex_);
    if (!accepted(batch)) {
        return;
    }
    Gateway& gateway = heard_from(batch->gateway);
    for (const std::uint32_t id : batch->entries) {
        if (owns(batch->gateway, id)) {
            owner_.erase(id);
            gateway.players.erase(id);
            leaving_.push_back(id);
        }
    }
}

void WorldProcess::tick() {
    {
        const std::lock_guard lock(mutex_);
        // Gateways silent past the timeout: their players leave with them. After the
        // world's own connection came back, every gateway gets a whole timeout again: it
        // could not be heard meanwhile.
        const auto now = std::chrono::steady_clock::now();
        if (const std::uint64_t reconnects = link_.reconnects(); reconnects != seen_reconnects_) {
            seen_reconnects_ = reconnects;
            for (auto& [id, gateway] : gateways_) {
                gateway.last_heard = now;
            }
        }
        for (auto it = gateways_.begin(); it != gateways_.end();) {
            if (now - it->second.last_heard <= gateway_timeout_) {
                ++it;
                continue;
            }
            for (const std::uint32_t id : it->second.players) {
                owner_.erase(id);
                leaving_.push_back(id);
            }
            ++stats_.gateways_lost;
            it = gateways_.erase(it);
        }
        // In id order, as the single-process server spawns them (GameWorld keeps
        // entities in id order whatever the order; the spawn points are dealt in turn).
        std::sort(joining_.begin(), joining_.end());
        for (const std::uint32_t id : joining_) {
            if (owner_.count(id) != 0) { // not left before its first tick
                world_.spawn_reserved(id);
            }
        }
        joining_.clear();
        for (const std::uint32_t id : leaving_) {
            world_.remove(id); // an id never spawned is ignored
            inputs_.erase(id);
        }
        stats_.leaves += leaving_.size();
        leaving_.clear();
        // The world keeps each player's intent until the next input changes it.
        for (const auto& [id, in] : inputs_) {
            world_.set_player_input(id, in.wish, in.jump, in.yaw_deg, in.pitch_deg);
            if (in.fire) {
                world_.fire(id);
            }
        }
        stats_.inputs += inputs_.size();
        inputs_.clear();
        // The moves: no callback changes the world meanwhile (joins reserve under the lock).
        world_.step(dt_);
        ++tick_;
        ++stats_.ticks;
        encode_world_tick(world_, key_, tick_, bytes_, monotonic_ns());
    }
    if (!link_.publish(world_subject(name_, "tick"), bytes_)) {
        const std::lock_guard lock(mutex_);
        ++stats_.ticks_not_published;
    }
}

WorldProcessStats WorldProcess::stats() const {
    const std::lock_guard lock(mutex_);
    return stats_;
}

} // namespace dsoc::scaleout
