#pragma once
// Checks of a replication trace (dsoc/trace/trace_reader.hpp) that tests of the server
// and of the evaluation both make.

#include "dsoc/trace/trace_reader.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

namespace dsoc::testing {

/// Reads the trace at `path` to its end and expects it to read without error and every
/// entity a client hears in a tick to be one that client is sent (heard within
/// replicated). Returns how many heard entries it holds, over every tick and client.
inline std::size_t expect_heard_are_replicated(const std::string& path) {
    trace::TraceReader reader;
    if (!reader.open(path)) {
        ADD_FAILURE() << "cannot read the trace " << path << ": " << reader.error();
        return 0;
    }
    trace::TraceTick tick;
    std::size_t heard = 0;
    while (reader.next(tick)) {
        for (const trace::TraceClient& client : tick.clients) {
            for (const std::uint32_t id : client.heard) {
                EXPECT_TRUE(
                    std::binary_search(client.replicated.begin(), client.replicated.end(), id))
                    << "tick " << tick.t << ": heard " << id << " is not replicated";
            }
            heard += client.heard.size();
        }
    }
    EXPECT_TRUE(reader.error().empty()) << reader.error();
    return heard;
}

} // namespace dsoc::testing
