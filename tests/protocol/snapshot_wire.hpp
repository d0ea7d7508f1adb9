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

/// "kind (detail) " for every problem, for a failure message.
inline std::string kinds(const std::vector<SnapshotProblem>& problems) {
    std::string out;
    for (const auto& p : problems) {
        out += p.kind + " (" + p.detail + ") ";
    }
    return out;
}

} // namespace dsoc::protocol
