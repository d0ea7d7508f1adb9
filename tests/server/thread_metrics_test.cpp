// Thread metrics (server/thread_metrics.hpp): the kernel's run and run-queue wait of the
// server's threads, summed by role. The parser reads schedstat's three numbers and
// nothing else; on this process a worker pool's busy threads show under "worker".

#include "dsoc/server/thread_metrics.hpp"
#include "dsoc/server/worker_pool.hpp"

#include <gtest/gtest.h>

#include <pthread.h>

#include <array>
#include <chrono>
#include <ctime>
#include <exception>
#include <string>

namespace dsoc::server {
namespace {

TEST(ThreadMetrics, ParsesTheThreeNumbersOfSchedstat) {
    const auto s = parse_schedstat("12000000000 3500000000 42\n");
    ASSERT_TRUE(s.has_value());
    EXPECT_DOUBLE_EQ(s->run_seconds, 12.0);
    EXPECT_DOUBLE_EQ(s->wait_seconds, 3.5);
    EXPECT_DOUBLE_EQ(s->timeslices, 42.0);
    EXPECT_TRUE(parse_schedstat("1 2 3").has_value()); // no newline
    for (const char* bad : {"", "\n", "1 2\n", "1 x 3\n", "1 2 3 4\n", "-1 2 3\n", "1 2 3x"}) {
        EXPECT_FALSE(parse_schedstat(bad).has_value()) << '"' << bad << '"';
    }
}

double thread_cpu_seconds() {
    timespec t{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

/// Spins the calling thread for `seconds` of its CPU time.
void spin(double seconds) {
    const double until = thread_cpu_seconds() + seconds;
    while (thread_cpu_seconds() < until) {
    }
}

TEST(ThreadMetrics, TheIoThreadAndThePoolsThreadsEachCountUnderTheirRole) {
    mark_io_thread(); // this test's thread stands for the I/O thread
    const ThreadRoleSample before = read_thread_roles();
    if (!before.read) {
        GTEST_SKIP() << "this kernel keeps no /proc/self/task/*/schedstat";
    }
    constexpr double kBusySeconds = 0.05; // of CPU, on each of the pool's threads
    WorkerPool pool(2, WorkerPool::Caller::stays_out);
    std::array<std::array<char, 16>, 2> names{};
    // start(): on the pool's own threads only (run() would let this thread take part).
    pool.start(
        2,
        [&](std::size_t i) {
            spin(kBusySeconds);
            ::pthread_getname_np(::pthread_self(), names[i].data(), names[i].size());
        },
        [](const std::exception_ptr&) {});
    pool.wait_idle();
    const double io_cpu_before = thread_cpu_seconds();
    spin(0.02);
    const double io_spun = thread_cpu_seconds() - io_cpu_before;
    const ThreadRoleSample after = read_thread_roles();
    ASSERT_TRUE(after.read);
    for (const auto& name : names) { // named as the metrics expect
        EXPECT_EQ(std::string(name.data()), WorkerPool::kThreadName);
    }
    EXPECT_GE(after.workers.run_seconds - before.workers.run_seconds, 2 * kBusySeconds * 0.9);
    EXPECT_GE(after.workers.timeslices - before.workers.timeslices, 2.0);
    // The kernel's run time and the thread's CPU clock are the same count.
    EXPECT_GE(after.io.run_seconds - before.io.run_seconds, io_spun * 0.9);
    // The pool's busy loops are not this thread's.
    EXPECT_LT(after.io.run_seconds - before.io.run_seconds, io_spun + kBusySeconds);
}

TEST(ThreadMetrics, AThreadThatEndedKeepsCounting) {
    const ThreadRoleSample first = read_thread_roles();
    if (!first.read) {
        GTEST_SKIP() << "this kernel keeps no /proc/self/task/*/schedstat";
    }
    double while_alive = 0.0;
    {
        WorkerPool pool(1, WorkerPool::Caller::stays_out);
        pool.start(
            1, [](std::size_t) { spin(0.03); }, [](const std::exception_ptr&) {});
        pool.wait_idle();
        while_alive = read_thread_roles().workers.run_seconds;
    } // the pool's thread ends here
    const ThreadRoleSample after = read_thread_roles();
    EXPECT_GE(while_alive - first.workers.run_seconds, 0.03 * 0.9);
    EXPECT_GE(after.workers.run_seconds, while_alive); // a counter never goes back
}

TEST(ThreadMetrics, WritesASamplePerRoleAndNothingUnread) {
    ThreadRoleSample sample;
    sample.io = {1.0, 0.25, 10};
    sample.workers = {6.0, 2.5, 40};
    sample.other = {0.5, 0.0, 3};
    sample.read = true;
    PrometheusText out;
    write_thread_metrics(out, sample);
    const std::string& t = out.text();
    for (const char* line : {"dsoc_thread_cpu_seconds_total{role=\"io\"} 1\n",
                             "dsoc_thread_cpu_seconds_total{role=\"worker\"} 6\n",
                             "dsoc_thread_runqueue_wait_seconds_total{role=\"io\"} 0.25\n",
                             "dsoc_thread_runqueue_wait_seconds_total{role=\"worker\"} 2.5\n",
                             "dsoc_thread_runqueue_wait_seconds_total{role=\"other\"} 0\n"}) {
        EXPECT_NE(t.find(line), std::string::npos) << line << t;
    }
    EXPECT_NE(t.find("# TYPE dsoc_thread_runqueue_wait_seconds_total counter\n"), std::string::npos)
        << t;
    PrometheusText none;
    write_thread_metrics(none, ThreadRoleSample{});
    EXPECT_EQ(none.text(), "");
}

} // namespace
} // namespace dsoc::server
