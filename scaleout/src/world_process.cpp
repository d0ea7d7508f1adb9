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
      instance_(random_id()), gateway_timeout_(gateway_timeout) {
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

bool WorldProcess::for_us(std::uint64_t instance) {
    if (instance != instance_) {
        ++stats_.other_instance;
    }
    return instance == instance_;
}

template <typename T>
bool WorldProcess::accepted(const maps::Result<T>& decoded) {
    if (!decoded.ok()) {
        refuse(decoded.error().message());
    }
    return decoded.ok();
}

WorldProcess::Gateway& WorldProcess::heard_from(std::uint64_t id) {
    Gateway& gateway = gateways_[id];
    gateway.last_heard = std::chrono::steady_clock::now();
    if (gateway.lost != 0) {
        gateway.lost = 0;
        ++stats_.gateways_back;
    }
    return gateway;
}

bool WorldProcess::make_room(std::size_t count) {
    while (reserved_ + count > kMaxReserved) {
        auto longest_lost = gateways_.end();
        for (auto it = gateways_.begin(); it != gateways_.end(); ++it) {
            if (it->second.lost != 0 &&
                (longest_lost == gateways_.end() || it->second.lost < longest_lost->second.lost)) {
                longest_lost = it;
            }
        }
        if (longest_lost == gateways_.end()) {
            return false;
        }
        reserved_ -= longest_lost->second.reserved.size();
        gateways_.erase(longest_lost);
        ++stats_.gateways_forgotten;
    }
    return true;
}

std::optional<IdBlock> WorldProcess::reserve_for(std::uint64_t gateway_id, std::uint32_t count,
                                                 const std::string& subject) {
    Gateway& gateway = heard_from(gateway_id);
    // Before make_room: ids that cannot be handed out forget no lost gateway.
    if (world_.ids_left() < count) {
        ++stats_.ids_exhausted;
        stats_.last_error = subject + ": " + std::to_string(count) + " ids asked for, " +
                            std::to_string(world_.ids_left()) + " left below 2^32";
        return std::nullopt;
    }
    if (!make_room(count)) {
        refuse(subject + ": " + std::to_string(reserved_) +
               " ids reserved and not joined already (at most " + std::to_string(kMaxReserved) +
               ")");
        return std::nullopt;
    }
    // tick() steps under the same lock, so no step sees half a block.
    const IdBlock block{key_, instance_, world_.reserve_players(count), count};
    for (std::uint32_t i = 0; i < count; ++i) {
        gateway.reserved.insert(block.first_id + i);
    }
    reserved_ += count;
    stats_.ids_reserved += count;
    return block;
}

void WorldProcess::on_reserve(const NatsMessage& message) {
    const std::string subject(message.subject);
    auto request = decode_reserve_request(message.data, subject);
    std::optional<IdBlock> block;
    {
        const std::lock_guard lock(mutex_);
        if (!accepted(request)) {
            return;
        }
        if (message.reply.empty()) {
            refuse(subject + ": a reserve request without a reply subject");
            return;
        }
        if (!for_us(request->instance)) {
            return;
        }
        block = reserve_for(request->gateway, request->count, subject);
    }
    if (block) {
        std::vector<std::byte> bytes;
        encode_id_block(*block, bytes);
        (void)link_.publish(message.reply, bytes); // lost: the gateway asks again
    }
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
    if (!accepted(batch) || !for_us(batch->instance)) {
        return;
    }
    Gateway& gateway = heard_from(batch->gateway);
    for (const std::uint32_t id : batch->entries) {
        if (gateway.players.count(id) != 0) {
            ++stats_.repeated; // a re-sent join that had arrived after all
        } else if (gateway.reserved.erase(id) != 0) {
            --reserved_;
            gateway.players.insert(id);
            joining_.emplace_back(batch->gateway, id);
            ++stats_.joins;
        } else {
            ++stats_.for_strangers; // never reserved for this gateway
        }
    }
}

void WorldProcess::on_input(const NatsMessage& message) {
    auto batch = decode_inputs(message.data, std::string(message.subject));
    const std::lock_guard lock(mutex_);
    if (!accepted(batch) || !for_us(batch->instance)) {
        return;
    }
    const Gateway& gateway = heard_from(batch->gateway);
    for (const PlayerInput& in : batch->entries) {
        if (gateway.players.count(in.entity_id) != 0) {
            PlayerInput& newest = inputs_[in.entity_id];
            const bool fired = newest.fire; // a shot is never lost to a newer input
            newest = in;
            newest.fire = newest.fire || fired;
        } else if (gateway.reserved.count(in.entity_id) == 0) {
            ++stats_.for_strangers; // a bot, another gateway's, a player who left
        }                           // else its player, removed while it was lost, not re-joined yet
    }
}

void WorldProcess::on_leave(const NatsMessage& message) {
    auto batch = decode_id_batch(IdBatchKind::leave, message.data, std::string(message.subject));
    const std::lock_guard lock(mutex_);
    if (!accepted(batch) || !for_us(batch->instance)) {
        return;
    }
    Gateway& gateway = heard_from(batch->gateway);
    for (const std::uint32_t id : batch->entries) {
        if (gateway.players.erase(id) != 0) {
            leaving_.push_back(id);
        } else if (gateway.reserved.erase(id) != 0) {
            --reserved_; // its join never arrived, or it left while its gateway was lost
        } else if (world_.find(id) == nullptr ||
                   std::find(leaving_.begin(), leaving_.end(), id) != leaving_.end()) {
            ++stats_.repeated; // a re-sent leave: gone already, or going at the next step
        } else {
            ++stats_.for_strangers; // a bot, another gateway's player
        }
    }
}

void WorldProcess::lose_silent_gateways(std::chrono::steady_clock::time_point now) {
    for (auto it = gateways_.begin(); it != gateways_.end();) {
        Gateway& gateway = it->second;
        if (gateway.lost != 0 || now - gateway.last_heard <= gateway_timeout_) {
            ++it;
            continue;
        }
        for (const std::uint32_t id : gateway.players) {
            leaving_.push_back(id);
            gateway.reserved.insert(id); // for its re-join, should it come back
        }
        reserved_ += gateway.players.size();
        gateway.players.clear();
        gateway.lost = ++losses_;
        ++stats_.gateways_lost;
        if (gateway.reserved.empty()) {
            it = gateways_.erase(it); // nothing to keep for it
        } else {
            ++it;
        }
    }
}

void WorldProcess::spawn_and_remove() {
    spawning_.clear();
    for (const auto& [gateway, id] : joining_) {
        const auto it = gateways_.find(gateway);
        if (it != gateways_.end() && it->second.players.count(id) != 0 &&
            world_.find(id) == nullptr) { // not left (or lost) before its first step
            spawning_.push_back(id);
        }
    }
    joining_.clear();
    // Each batch in one pass (a lost gateway's hundreds of players, or their return,
    // cost one rebuild, not one each), in id order as the single-process server spawns
    // them (an id joined twice, lost in between, spawns once).
    world_.spawn_reserved(spawning_);
    world_.remove(leaving_); // an id never spawned is ignored
    for (const std::uint32_t id : leaving_) {
        inputs_.erase(id);
    }
    stats_.leaves += leaving_.size();
    leaving_.clear();
}

void WorldProcess::tick() {
    {
        const std::lock_guard lock(mutex_);
        // After the world's own connection came back, every gateway gets a whole
        // timeout again: it could not be heard meanwhile.
        const auto now = std::chrono::steady_clock::now();
        if (const std::uint64_t reconnects = link_.reconnects(); reconnects != seen_reconnects_) {
            seen_reconnects_ = reconnects;
            for (auto& [id, gateway] : gateways_) {
                gateway.last_heard = now;
            }
        }
        lose_silent_gateways(now);
        spawn_and_remove();
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
        encode_world_tick(world_, key_, tick_, bytes_, monotonic_ns(), instance_);
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
