#include "dsoc/server/gateway_ids.hpp"

#include <algorithm>
#include <iterator>

namespace dsoc::server {

namespace {

/// Whether `entities` (in increasing id order) hold `id`.
bool in_tick(std::span<const interest::Entity> entities, std::uint32_t id) {
    const auto it = std::lower_bound(
        entities.begin(), entities.end(), id,
        [](const interest::Entity& e, std::uint32_t wanted) { return e.id < wanted; });
    return it != entities.end() && it->id == id;
}

/// Whether a message sent at `sent` has had its time to show at `now`.
bool due(GatewayIds::Clock::time_point sent, GatewayIds::Clock::time_point now) {
    return now - sent >= GatewayIds::kResendAfter;
}

} // namespace

void GatewayIds::add_block(std::uint32_t first, std::uint32_t count) {
    const auto at = std::upper_bound(blocks_.begin(), blocks_.end(), first,
                                     [](std::uint32_t id, const Block& b) { return id < b.first; });
    blocks_.insert(at, Block{first, count});
    for (std::uint32_t i = 0; i < count; ++i) {
        unused_.push_back(first + i);
    }
}

std::uint32_t GatewayIds::take() {
    if (unused_.empty()) {
        return 0;
    }
    const std::uint32_t id = unused_.front();
    unused_.pop_front();
    return id;
}

bool GatewayIds::ours(std::uint32_t id) const {
    // The last block starting at or before `id`.
    const auto after =
        std::upper_bound(blocks_.begin(), blocks_.end(), id,
                         [](std::uint32_t v, const Block& b) { return v < b.first; });
    return after != blocks_.begin() && id - std::prev(after)->first < std::prev(after)->count;
}

bool GatewayIds::given_out(std::uint32_t id) const {
    return ours(id) && std::find(unused_.begin(), unused_.end(), id) == unused_.end();
}

std::vector<std::uint32_t> GatewayIds::join(std::span<const std::uint32_t> ids,
                                            Clock::time_point now) {
    std::vector<std::uint32_t> out;
    for (const std::uint32_t id : ids) {
        if (given_out(id)) {
            joined_[id] = now;
            out.push_back(id);
        }
    }
    return out;
}

std::vector<std::uint32_t> GatewayIds::leave(std::span<const std::uint32_t> ids,
                                             Clock::time_point now) {
    std::vector<std::uint32_t> out;
    for (const std::uint32_t id : ids) {
        if (given_out(id)) {
            joined_.erase(id);
            left_[id] = now;
            out.push_back(id);
        }
    }
    return out;
}

GatewayIds::Resend GatewayIds::check(std::span<const interest::Entity> entities,
                                     Clock::time_point now) {
    Resend resend;
    // A player of ours the world does not have: its join was lost (or the world removed
    // it, as it does a gateway it has not heard for its timeout).
    for (auto& [id, sent] : joined_) {
        if (due(sent, now) && !in_tick(entities, id)) {
            resend.joins.push_back(id);
            sent = now;
        }
    }
    // An id of ours the world has though no player of ours holds it: its leave was lost.
    for (const interest::Entity& e : entities) {
        if (e.kind != interest::EntityKind::player || !ours(e.id) || joined_.count(e.id) != 0) {
            continue;
        }
        // Never sent from here (a time_point of 0 is long due): sent at once.
        auto [it, added] = left_.try_emplace(e.id, Clock::time_point{});
        if (due(it->second, now)) {
            resend.leaves.push_back(e.id);
            it->second = now;
        }
    }
    // Left and gone once its leave had its time (a tick taken before the world had it
    // may still show it): nothing more to watch.
    std::erase_if(left_, [&](const auto& entry) {
        return due(entry.second, now) && !in_tick(entities, entry.first);
    });
    std::sort(resend.joins.begin(), resend.joins.end());
    return resend;
}

void GatewayIds::clear() {
    blocks_.clear();
    unused_.clear();
    joined_.clear();
    left_.clear();
}

} // namespace dsoc::server
