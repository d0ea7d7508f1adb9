#pragma once
// Reads and validates a replication trace. Every problem is reported with the line
// number and what is wrong; reading never throws.

#include "dsoc/trace/trace_types.hpp"

#include <fstream>
#include <string>

namespace dsoc::trace {

class TraceReader {
public:
    /// Opens the file and reads the header line. False with error() set on failure.
    [[nodiscard]] bool open(const std::string& path);
    /// Reads the next tick line into `tick`. False at the end line (then
    /// finished() is true) or on an error (then error() is non-empty).
    [[nodiscard]] bool next(TraceTick& tick);

    [[nodiscard]] const TraceHeader& header() const { return header_; }
    [[nodiscard]] const std::string& error() const { return error_; }
    /// True once the end line was read and its tick count matched.
    [[nodiscard]] bool finished() const { return finished_; }
    [[nodiscard]] std::uint64_t ticks_read() const { return ticks_; }

private:
    bool fail(const std::string& what);

    std::ifstream in_;
    std::string path_;
    std::uint64_t line_number_ = 0;
    TraceHeader header_;
    std::string error_;
    bool finished_ = false;
    std::uint64_t ticks_ = 0;
    bool any_tick_ = false;
    std::uint64_t last_t_ = 0;
};

} // namespace dsoc::trace
