#pragma once
// Where the server's threads spend the wall time they do not run: waiting for a core.
// The kernel counts, per thread, the time it ran and the time it was ready to run but
// waited on a run queue (/proc/<pid>/task/<tid>/schedstat). A tick that overruns while
// its threads waited long says the machine is oversubscribed (a co-located load, noisy
// neighbours, more threads than cores), not that the server's work grew. Linux only,
// and only where the kernel keeps schedstat (CONFIG_SCHED_INFO); else nothing is read.

#include "dsoc/server/metrics.hpp"

#include <optional>
#include <string_view>

namespace dsoc::server {

/// One thread's line of schedstat: three numbers.
struct SchedStat {
    double run_seconds = 0.0;  ///< time on a core [s]
    double wait_seconds = 0.0; ///< time ready to run, waiting on a run queue [s]
    double timeslices = 0.0;   ///< how many times it was put on a core
};

/// Parses "<run ns> <wait ns> <timeslices>\n"; nothing when the text is not that.
[[nodiscard]] std::optional<SchedStat> parse_schedstat(std::string_view text);

/// The process's threads summed by role: the I/O thread (the main thread, whose id is
/// the process's), the worker pool's (named WorkerPool::kThreadName) and every other.
struct ThreadRoleSample {
    SchedStat io;
    SchedStat workers;
    SchedStat other;
    bool read = false; ///< false where schedstat could not be read
};

/// Reads /proc/self/task/*/{comm,schedstat}. A thread that ends during the listing is
/// left out. Thread-safe.
[[nodiscard]] ThreadRoleSample read_thread_roles();

/// dsoc_thread_cpu_seconds_total and dsoc_thread_runqueue_wait_seconds_total, a sample
/// per role ("io", "worker", "other"); nothing when `sample` was not read.
void write_thread_metrics(PrometheusText& out, const ThreadRoleSample& sample);

} // namespace dsoc::server
