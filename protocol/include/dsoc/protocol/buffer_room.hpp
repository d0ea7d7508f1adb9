#pragma once
// The memory rule of every buffer a connection refills each tick (acknowledged-delta
// frames, snapshot messages, update columns, datagram scratch): room follows what the
// connection needs now, not the most it ever needed. A buffer keeps its room while that
// room is at most twice what it held at its last use, plus a slack; beyond that it is
// given back and grows again from what the next use needs. Without the rule each of
// hundreds of connections kept its largest moment so far (a burst of enters, a catch-up
// after loss) for the rest of its life, and a long run's memory crept up with every such
// moment of every client.
//
// Threading: none; each buffer belongs to one connection.

#include "dsoc/protocol/messages.hpp"

#include <cstddef>
#include <vector>

namespace dsoc::protocol {

/// Whether a buffer with room for `room` items, which held `used` at its last use, keeps
/// more than it needs: room > 2 * used + slack.
[[nodiscard]] constexpr bool room_oversized(std::size_t room, std::size_t used, std::size_t slack) {
    return room > 2 * used + slack;
}

/// Empties `buffer` for its next use (its size is the last use), keeping its memory
/// unless room_oversized(capacity, size, slack), when the memory is given back.
template <class T>
void clear_to_need(std::vector<T>& buffer, std::size_t slack) {
    if (room_oversized(buffer.capacity(), buffer.size(), slack)) {
        std::vector<T>().swap(buffer);
    } else {
        buffer.clear();
    }
}

/// Room kept beyond twice the last use of a snapshot message's repeated fields. [Units:
/// entries]
inline constexpr std::size_t kSnapshotSlackEntries = 64;

/// Clears `snapshot` (its fields are the last snapshot's) for the next one, as Clear()
/// does, but gives back all its memory - the room of its repeated fields and the entity
/// messages protobuf keeps for reuse - when any repeated field's room is
/// room_oversized() against what the last snapshot put in it.
void clear_to_need(pb::Snapshot& snapshot);

} // namespace dsoc::protocol
