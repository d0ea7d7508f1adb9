#pragma once
// An interest gateway's entity ids in one world instance (docs/scale-out.md, "Faults"):
// the blocks the world process reserved for it, which of them it gave to players, joined
// to the world and had leave, what each world tick shows lost on the way, and how many
// ids to ask the world for next.
//
// NATS delivers at most once, so joins and leaves can be lost (the world's connection
// was down when one was sent). The tick stream is their acknowledgement, since every
// tick lists every entity:
// - a player the gateway joined that a tick lacks kResendAfter or more after its join
//   was last sent has its join sent again, kJoinResends times at most; a join still not
//   shown after that is given up (abandoned): the world does not hold that id for the
//   gateway any more (it took the gateway for lost and then forgot it to make room for
//   other reservations), so the player's session must end (its client connects again
//   and gets a fresh id), a leave is sent for the id (blind, as below: should the world
//   hold it after all, it is released), and the ids not given out yet of its block and
//   of every earlier one are void too (reserved before the world forgot the gateway)
//   and dropped;
// - an id the gateway gave out that a tick shows though none of its players holds it
//   (it left) has its leave sent again, kResendAfter or more after the last one;
// - a leave of an id the last tick checked did not show (its join lost or still on its
//   way, its player removed with a gateway the world took for lost, a client gone
//   before its first tick) has no tick to acknowledge it, yet the world keeps that id
//   reserved for the gateway until a leave arrives: it is sent again kBlindResends
//   times, kResendAfter apart, unless a tick shows the player meanwhile (then the rule
//   above takes over).
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
    /// Re-sends of a leave no tick can acknowledge (above): with kResendAfter, it reaches
    /// a world whose connection to NATS is back within this many seconds. [Limit: re-sends]
    static constexpr int kBlindResends = 5;
    /// Re-sends of a join no tick shows before it is abandoned (above): with kResendAfter,
    /// a world that holds the id for the gateway spawns the player well within that, so
    /// only a world that forgot the gateway lets them all go by. [Limit: re-sends]
    static constexpr int kJoinResends = 5;
    /// Ids asked for at a time when nothing more is wanted: a second's joins of a busy
    /// gateway. A request is due when fewer than half of it are left. [Units: ids]
    static constexpr std::uint32_t kIdBlock = 256;

    /// Adds [first, first + count) to the ids this gateway may give out; they meet that
    /// much of the demand (to_reserve()).
    void add_block(std::uint32_t first, std::uint32_t count);
    /// An id not given out yet (the oldest block's first), or 0 when none is left: then
    /// the demand grows by one (a client that will try again).
    [[nodiscard]] std::uint32_t take();
    /// Ids not given out yet.
    [[nodiscard]] std::size_t left() const { return unused_.size(); }
    /// How many ids to ask the world for now: 0 while at least kIdBlock / 2 are left and
    /// they cover the demand; else the demand not covered plus kIdBlock, at most
    /// scaleout::kMaxIdBlock (one request's limit). [Units: ids]
    [[nodiscard]] std::uint32_t to_reserve() const;

    /// Whether `id` was given out by take() since the last clear().
    [[nodiscard]] bool given_out(std::uint32_t id) const { return given_.count(id) != 0; }

    /// Of `ids`, those given out, now joined: their joins are sent at `now`.
    [[nodiscard]] std::vector<std::uint32_t> join(std::span<const std::uint32_t> ids,
                                                  Clock::time_point now);
    /// Of `ids`, those given out, now left: their leaves are sent at `now`.
    [[nodiscard]] std::vector<std::uint32_t> leave(std::span<const std::uint32_t> ids,
                                                   Clock::time_point now);

    /// Joins and leaves to send again, each in increasing id order, and the joins given
    /// up.
    struct Resend {
        std::vector<std::uint32_t> joins;
        std::vector<std::uint32_t> leaves; ///< the abandoned joins' ids among them
        /// Players whose joins were given up (kJoinResends): their sessions must end.
        std::vector<std::uint32_t> abandoned;
        /// Ids not given out yet that the abandoned joins showed void: dropped. [Units: ids]
        std::size_t voided = 0;
    };
    /// What a world tick's `entities` (in increasing id order, as decoded) show lost at
    /// `now`; the re-sends it returns count as sent at `now`. An abandoned player counts
    /// as left, and its client as one more id wanted (it connects again).
    [[nodiscard]] Resend check(std::span<const interest::Entity> entities, Clock::time_point now);

    /// Forgets every id: those of one world instance mean nothing to another. The
    /// players that held one (given out, not left) are the demand for the next block:
    /// their sessions end with that instance, and their clients come back together.
    void clear();

private:
    struct Joined {
        Clock::time_point sent; ///< when its join was last sent
        bool shown = false;     ///< in the last tick checked
        int resends = 0;        ///< since a tick last showed it
    };
    struct Left {
        Clock::time_point sent; ///< when its leave was last sent
        int blind_resends = 0;  ///< re-sends left while no tick shows it
    };
    /// Drops the ids not given out of the block holding `id` and of every earlier block;
    /// how many.
    std::size_t void_through(std::uint32_t id);

    std::deque<std::uint32_t> unused_; ///< not given out, oldest block first
    /// One past the last id of each block added since clear(), increasing (the world
    /// hands out increasing ids): which block an id is of.
    std::vector<std::uint32_t> block_ends_;
    /// Given out since clear(): true while held (not left).
    std::unordered_map<std::uint32_t, bool> given_;
    std::size_t held_ = 0; ///< given_ entries still held
    /// Ids wanted beyond those left: see to_reserve(). [Units: ids]
    std::size_t wanted_ = 0;
    /// Joined and not left.
    std::unordered_map<std::uint32_t, Joined> joined_;
    /// Left, and in the ticks since, or sent within kResendAfter, or blind re-sends left.
    std::unordered_map<std::uint32_t, Left> left_;
};

} // namespace dsoc::server
