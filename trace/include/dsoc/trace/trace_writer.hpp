#pragma once
// Streams a replication trace to a file, one JSON object per line, exactly as the
// spec says: the header, then tick lines in increasing t, then the end line.

#include "dsoc/trace/trace_types.hpp"

#include <cstdio>
#include <string>

namespace dsoc::trace {

class TraceWriter {
public:
    TraceWriter() = default;
    ~TraceWriter();
    TraceWriter(const TraceWriter&) = delete;
    TraceWriter& operator=(const TraceWriter&) = delete;

    /// Opens `path` for writing and writes the header. False (with `error` set) when
    /// the file cannot be opened or written.
    [[nodiscard]] bool open(const std::string& path, const TraceHeader& header, std::string& error);
    /// Writes one tick line. Ticks must be written in increasing `t`; a tick that is
    /// not increasing is refused (false).
    bool write_tick(const TraceTick& tick);
    /// Writes the end line and closes. Safe to call twice; the destructor calls it.
    bool close();

    [[nodiscard]] bool is_open() const { return file_ != nullptr; }
    [[nodiscard]] std::uint64_t ticks_written() const { return ticks_; }

private:
    bool put(const std::string& line);

    std::FILE* file_ = nullptr;
    std::uint64_t ticks_ = 0;
    std::uint64_t last_t_ = 0;
    bool any_tick_ = false;
    std::string line_;
};

} // namespace dsoc::trace
