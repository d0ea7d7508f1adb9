#pragma once
// An interest gateway's entity ids in one world instance (docs/scale-out.md, "Faults"):
// the blocks the world process reserved for it, which of them it gave to players, joined
// to the world and had leave, and what each world tick shows lost on the way.
//
// NATS delivers at most once, so joins and leaves can be lost (the world's connection
// was down when one was sent). The tick stream is their acknowledgement, since every
// tick lists every entity:
// - a player the gateway joined that a tick lacks kResendAfter or more after its join
//   was last sent has its join sent again;
// - an id of the gateway's blocks that a tick shows though none of its players holds it
//   (it left) has its leave sent again, kResendAfter or more after the last one.
// The world takes a join of a player it has and a leave of one it no longer has as
// no-ops, so a re-send that crossed its original changes nothing.
//
// Threading: none (WorldFeed calls it under its lock).

#include "dsoc/interest/game_world.hpp"

#include <chrono>
#include <cstdint>
#include <deque>
#include <span>
#include <unordered_map>
#include <vector>

namespace dsoc::server {

class GatewayIds {
public:
    using Clock = std::chrono::steady_clock;
    /// How long a join or leave is given to show in the ticks before it is sent again:
    /// many world steps and hops, well under a client's patience. [Units: ms]
    static constexpr std::chrono::milliseconds kResendAfter{1000};

    /// Adds [first, first + count) to the ids this gateway may give out.
    void add_block(std::uint32_t first, std::uint32_t count);
    /// An id not given out yet (the oldest block's first), or 0 when none is left.
    [[nodiscard]] std::uint32_t take();
    /// Ids not given out yet.
    [[nodiscard]] std::size_t left() const { return unused_.size(); }
    /// Whether `id` is from one of this gateway's blocks.
    [[nodiscard]] bool ours(std::uint32_t id) const;

    /// Whether `id` was given out by take() since the last clear().
    [[nodiscard]] bool given_out(std::uint32_t id) const;

    /// Of `ids`, those given out, now joined: their joins are sent at `now`.
    [[nodiscard]] std::vector<std::uint32_t> join(std::span<const std::uint32_t> ids,
                                                  Clock::time_point now);
    /// Of `ids`, those given out, now left: their leaves are sent at `now`.
    [[nodiscard]] std::vector<std::uint32_t> leave(std::span<const std::uint32_t> ids,
                                                   Clock::time_point now);

    /// Joins and leaves to send again, each in increasing id order.
    struct Resend {
        std::vector<std::uint32_t> joins;
        std::vector<std::uint32_t> leaves;
    };
    /// What a world tick's `entities` (in increasing id order, as decoded) show lost at
    /// `now`; the re-sends it returns count as sent at `now`.
    [[nodiscard]] Resend check(std::span<const interest::Entity> entities, Clock::time_point now);

    /// Forgets every id: those of one world instance mean nothing to another.
    void clear();

private:
    struct Block {
        std::uint32_t first;
        std::uint32_t count;
    };
    std::vector<Block> blocks_;        ///< in increasing order of first id, never overlapping
    std::deque<std::uint32_t> unused_; ///< not given out, oldest block first
    /// Joined and not left: when its join was last sent.
    std::unordered_map<std::uint32_t, Clock::time_point> joined_;
    /// Left, and in the ticks since or sent within kResendAfter: when its leave was last
    /// sent.
    std::unordered_map<std::uint32_t, Clock::time_point> left_;
};

} // namespace dsoc::server
