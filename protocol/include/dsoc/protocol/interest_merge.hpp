#pragma once
// The rule behind every snapshot's enter / update / leave: one pass, in increasing id
// order, over what a client knows and what it should know now. The server's
// ReplicationState and dsoc-eval's ClientReplication both walk it, so that the
// evaluation's bytes come from the server's rule.

#include <cstddef>
#include <cstdint>

namespace dsoc::protocol {

/// Walks `known` (entity ids the client knows) and `wanted` (its new interest set),
/// both in increasing id order, merged by id: calls `on_leave(id)` for each known id
/// not wanted, and `on_wanted(index, was_known)` for each wanted[index] (id_of(wanted
/// [index]) its id), in id order. `known` must not change during the walk.
template <class KnownIds, class Wanted, class IdOf, class OnLeave, class OnWanted>
void merge_interest(const KnownIds& known, const Wanted& wanted, IdOf id_of, OnLeave&& on_leave,
                    OnWanted&& on_wanted) {
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < known.size() || j < wanted.size()) {
        const bool take_old =
            j == wanted.size() || (i < known.size() && known[i] < id_of(wanted[j]));
        const bool take_new =
            i == known.size() || (j < wanted.size() && id_of(wanted[j]) < known[i]);
        if (take_old) { // known, no longer of interest
            on_leave(static_cast<std::uint32_t>(known[i]));
            ++i;
            continue;
        }
        if (!take_new) {
            ++i; // known and still of interest
        }
        on_wanted(j, !take_new);
        ++j;
    }
}

} // namespace dsoc::protocol
