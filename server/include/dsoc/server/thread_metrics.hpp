#pragma once
// Where the server's threads spend the wall time they do not run: waiting for a core.
// The kernel counts, per thread, the time it ran and the time it was ready to run but
// waited on a run queue (/proc/<pid>/task/<tid>/schedstat). A tick that overruns while
// its threads waited long says the machine is oversubscribed (a co-located load, noisy
// neighbours, more threads than cores), not that the server's work grew. Linux only,
// and only where the kernel keeps schedstat (CONFIG_SCHED_INFO, and on: a kernel with it
// off reads 0 everywhere); else nothing is read.

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

/// Marks the calling thread as the one serving the sockets (the io_context's): its time
/// counts under "io". The last thread marked is the I/O thread; call it wherever an
/// io_context starts running for the server. Thread-safe.
void mark_io_thread();

/// The process's threads summed by role since the first call: the I/O thread
/// (mark_io_thread()), the worker pool's (named WorkerPool::kThreadName) and every other
/// (the allocator's background threads, a bake's threads at start-up, libnats' threads,
/// a world process's tick loop). A thread that has ended keeps counting under the role
/// it last had, so every figure only grows.
struct ThreadRoleSample {
    SchedStat io;
    SchedStat workers;
    SchedStat other;
    bool read = false; ///< false where schedstat could not be read
};

/// Reads /proc/self/task/*/{comm,schedstat} and adds the threads that ended since the
/// last call at what they had then. Thread-safe (one call at a time, under a lock).
[[nodiscard]] ThreadRoleSample read_thread_roles();

/// dsoc_thread_cpu_seconds_total and dsoc_thread_runqueue_wait_seconds_total, a sample
/// per role ("io", "worker", "other"); nothing when `sample` was not read.
void write_thread_metrics(PrometheusText& out, const ThreadRoleSample& sample);

} // namespace dsoc::server
