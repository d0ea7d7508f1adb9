#pragma once
// What the snapshot codec tests share: a snapshot sent through the wire and a
// problem list made readable.

#include "dsoc/protocol/compact_snapshot.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace dsoc::protocol {

/// Serializes and parses, so that the decoder sees exactly what travels.
inline pb::Snapshot through_wire(const pb::Snapshot& s) {
    pb::Snapshot out;
    EXPECT_TRUE(out.ParseFromString(s.SerializeAsString()));
    return out;
}

/// Appends an update entry's head `id_step` after the previous entry (the first: its
/// id) with field mask `fields` (its mask apart too when the wire puts it there), as an
/// encoder writes it; a test adds the values.
inline void add_entry(pb::Snapshot& s, std::uint64_t id_step, std::uint32_t fields) {
    s.add_update_head(update_head(id_step, fields));
    if (mask_apart(fields)) {
        s.add_update_fields(fields);
    }
}

/// The field mask of `s`'s only or first update entry.
inline std::uint32_t first_entry_fields(const pb::Snapshot& s) {
    const auto head = static_cast<std::uint32_t>(s.update_head(0) & kHeadFields);
    return head != 0 ? head : s.update_fields(0);
}

/// "kind (detail) " for every problem, for a failure message.
inline std::string kinds(const std::vector<SnapshotProblem>& problems) {
    std::string out;
    for (const auto& p : problems) {
        out += p.kind + " (" + p.detail + ") ";
    }
    return out;
}

} // namespace dsoc::protocol
