#include "dsoc/protocol/buffer_room.hpp"

namespace dsoc::protocol {

namespace {

template <class Repeated>
bool oversized(const Repeated& field) {
    return room_oversized(static_cast<std::size_t>(field.Capacity()),
                          static_cast<std::size_t>(field.size()), kSnapshotSlackEntries);
}

} // namespace

void clear_to_need(pb::Snapshot& snapshot) {
    // A RepeatedPtrField's Capacity() bounds the entity messages it keeps for reuse.
    if (oversized(snapshot.enter()) || oversized(snapshot.leave()) ||
        oversized(snapshot.update_head()) || oversized(snapshot.update_fields()) ||
        oversized(snapshot.update_values()) || oversized(snapshot.audit())) {
        pb::Snapshot empty;
        snapshot.Swap(&empty); // `empty` takes the memory and frees it
        return;
    }
    snapshot.Clear();
}

} // namespace dsoc::protocol
