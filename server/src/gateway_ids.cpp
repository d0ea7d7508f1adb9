#include "dsoc/server/gateway_ids.hpp"

#include "dsoc/scaleout/world_messages.hpp"

#include <algorithm>

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
    for (std::uint32_t i = 0; i < count; ++i) {
        unused_.push_back(first + i);
    }
    block_ends_.push_back(first + count);
    wanted_ -= std::min<std::size_t>(wanted_, count);
}

std::size_t GatewayIds::void_through(std::uint32_t id) {
    const auto end = std::upper_bound(block_ends_.begin(), block_ends_.end(), id);
    const std::uint32_t below = end == block_ends_.end() ? UINT32_MAX : *end;
    std::size_t voided = 0;
    while (!unused_.empty() && unused_.front() < below) { // given out oldest first
        unused_.pop_front();
        ++voided;
    }
    return voided;
}

std::uint32_t GatewayIds::take() {
    if (unused_.empty()) {
        wanted_ = std::min<std::size_t>(wanted_ + 1, scaleout::kMaxIdBlock);
        return 0;
    }
    const std::uint32_t id = unused_.front();
    unused_.pop_front();
    given_.emplace(id, true);
    ++held_;
    return id;
}

std::uint32_t GatewayIds::to_reserve() const {
    const std::size_t short_by = wanted_ > left() ? wanted_ - left() : 0;
    if (short_by == 0 && left() >= kIdBlock / 2) {
        return 0;
    }
    return static_cast<std::uint32_t>(
        std::min<std::size_t>(short_by + kIdBlock, scaleout::kMaxIdBlock));
}

std::vector<std::uint32_t> GatewayIds::join(std::span<const std::uint32_t> ids,
                                            Clock::time_point now) {
    std::vector<std::uint32_t> out;
    for (const std::uint32_t id : ids) {
        if (given_out(id)) {
            joined_[id] = Joined{now, false};
            out.push_back(id);
        }
    }
    return out;
}

std::vector<std::uint32_t> GatewayIds::leave(std::span<const std::uint32_t> ids,
                                             Clock::time_point now) {
    std::vector<std::uint32_t> out;
    for (const std::uint32_t id : ids) {
        const auto given = given_.find(id);
        if (given == given_.end()) {
            continue;
        }
        if (given->second) {
            given->second = false;
            --held_;
        }
        const auto joined = joined_.find(id);
        const bool shown = joined != joined_.end() && joined->second.shown;
        if (joined != joined_.end()) {
            joined_.erase(joined);
        }
        // Shown: the ticks acknowledge it; else re-sent blind, a bounded number of times.
        left_[id] = Left{now, shown ? 0 : kBlindResends};
        out.push_back(id);
    }
    return out;
}

GatewayIds::Resend GatewayIds::check(std::span<const interest::Entity> entities,
                                     Clock::time_point now) {
    Resend resend;
    // A player of ours the world does not have: its join was lost (or the world removed
    // it, as it does a gateway it has not heard for its timeout). Given up once its
    // re-sends went by: the world does not hold its id for us.
    for (auto& [id, joined] : joined_) {
        joined.shown = in_tick(entities, id);
        if (joined.shown) {
            joined.resends = 0;
        } else if (due(joined.sent, now)) {
            (joined.resends < kJoinResends ? resend.joins : resend.abandoned).push_back(id);
            ++joined.resends;
            joined.sent = now;
        }
    }
    std::sort(resend.abandoned.begin(), resend.abandoned.end());
    for (const std::uint32_t id : resend.abandoned) {
        (void)leave(std::span(&id, 1), now); // blind: no tick shows it
        wanted_ = std::min<std::size_t>(wanted_ + 1, scaleout::kMaxIdBlock);
    }
    if (!resend.abandoned.empty()) {
        resend.voided = void_through(resend.abandoned.back());
    }
    resend.leaves = resend.abandoned; // sent now
    // An id we gave out that the world has though no player of ours holds it: its leave
    // was lost.
    for (const interest::Entity& e : entities) {
        if (e.kind != interest::EntityKind::player || !given_out(e.id) ||
            joined_.count(e.id) != 0) {
            continue;
        }
        // Never sent from here (a time_point of 0 is long due): sent at once.
        auto [it, added] = left_.try_emplace(e.id, Left{Clock::time_point{}, 0});
        it->second.blind_resends = 0; // shown: the ticks acknowledge it from now on
        if (due(it->second.sent, now)) {
            resend.leaves.push_back(e.id);
            it->second.sent = now;
        }
    }
    // Left, not shown, its leave had its time: sent again blind while it has re-sends
    // left, else nothing more to watch (a tick taken before the world had it may still
    // have shown it).
    for (auto it = left_.begin(); it != left_.end();) {
        Left& left = it->second;
        if (!due(left.sent, now) || in_tick(entities, it->first)) {
            ++it;
        } else if (left.blind_resends == 0) {
            it = left_.erase(it);
        } else {
            --left.blind_resends;
            left.sent = now;
            resend.leaves.push_back(it->first);
            ++it;
        }
    }
    std::sort(resend.joins.begin(), resend.joins.end());
    std::sort(resend.leaves.begin(), resend.leaves.end());
    return resend;
}

void GatewayIds::clear() {
    wanted_ = std::min<std::size_t>(wanted_ + held_, scaleout::kMaxIdBlock);
    unused_.clear();
    block_ends_.clear();
    given_.clear();
    held_ = 0;
    joined_.clear();
    left_.clear();
}

} // namespace dsoc::server
