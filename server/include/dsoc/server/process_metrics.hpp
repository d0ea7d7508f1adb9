#pragma once
// What /metrics says about the process and the build, beside the server's own
// figures: the standard process_* metrics of Prometheus' client libraries (same names,
// so existing dashboards and alerts work) and dsoc_build_info. Linux only (/proc).

#include "dsoc/server/metrics.hpp"

#include <string>
#include <string_view>

namespace dsoc::server {

/// One reading of the process. A field that could not be read is negative and is left
/// out of the metrics.
struct ProcessSample {
    double cpu_seconds = -1.0;        ///< user + system CPU time since start [s]
    double resident_bytes = -1.0;     ///< resident set size [bytes]
    double virtual_bytes = -1.0;      ///< virtual memory size [bytes]
    double open_fds = -1.0;           ///< open file descriptors
    double max_fds = -1.0;            ///< the soft limit on them (RLIMIT_NOFILE)
    double start_time_seconds = -1.0; ///< start of the process, Unix time [s]
    /// The C allocator's view (heap_stats.hpp): bytes of live allocations, and bytes it
    /// holds beyond them. RSS that grows with the second is the allocator keeping
    /// memory, not the server keeping data. [bytes]
    double heap_in_use_bytes = -1.0;
    double heap_free_bytes = -1.0;
    std::string_view allocator; ///< allocator_name() of the running one; empty if unread
};

/// Reads the calling process's figures from /proc and getrusage(), and the allocator's
/// (read_heap_sample(costly_heap): jemalloc's always, glibc's only with `costly_heap`).
/// Thread-safe. A few system calls and one directory listing (/proc/self/fd).
[[nodiscard]] ProcessSample read_process_sample(bool costly_heap = false);

/// process_cpu_seconds_total, process_resident_memory_bytes,
/// process_virtual_memory_bytes, process_open_fds, process_max_fds,
/// process_start_time_seconds, dsoc_heap_allocator_info, dsoc_heap_in_use_bytes and
/// dsoc_heap_free_bytes, for the fields of `sample` that were read.
void write_process_metrics(PrometheusText& out, const ProcessSample& sample);

/// dsoc_build_info{version="...",commit="..."} 1: the build that runs (commit empty
/// when the build did not know it).
void write_build_info(PrometheusText& out, std::string_view version, std::string_view commit);

} // namespace dsoc::server
