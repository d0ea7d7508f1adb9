#include "dsoc/server/thread_metrics.hpp"

#include "dsoc/server/worker_pool.hpp"

#include <dirent.h>
#include <unistd.h>

#include <charconv>
#include <fstream>
#include <iterator>
#include <string>

namespace dsoc::server {

std::optional<SchedStat> parse_schedstat(std::string_view text) {
    std::uint64_t numbers[3] = {};
    const char* at = text.data();
    const char* const end = text.data() + text.size();
    for (std::uint64_t& n : numbers) {
        while (at != end && *at == ' ') {
            ++at;
        }
        const auto [next, error] = std::from_chars(at, end, n);
        if (error != std::errc() || next == at) {
            return std::nullopt;
        }
        at = next;
    }
    if (at != end && *at != '\n') {
        return std::nullopt;
    }
    return SchedStat{static_cast<double>(numbers[0]) * 1e-9, static_cast<double>(numbers[1]) * 1e-9,
                     static_cast<double>(numbers[2])};
}

namespace {

std::string read_file(const std::string& path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void add(SchedStat& to, const SchedStat& s) {
    to.run_seconds += s.run_seconds;
    to.wait_seconds += s.wait_seconds;
    to.timeslices += s.timeslices;
}

} // namespace

ThreadRoleSample read_thread_roles() {
    ThreadRoleSample sample;
    DIR* dir = ::opendir("/proc/self/task");
    if (dir == nullptr) {
        return sample;
    }
    const std::string main_thread = std::to_string(::getpid());
    while (const dirent* entry = ::readdir(dir)) {
        const std::string tid = entry->d_name;
        if (tid == "." || tid == "..") {
            continue;
        }
        const std::string task = "/proc/self/task/" + tid;
        const auto stat = parse_schedstat(read_file(task + "/schedstat"));
        if (!stat) {
            continue; // ended meanwhile, or a kernel without schedstat
        }
        std::string name = read_file(task + "/comm");
        if (!name.empty() && name.back() == '\n') {
            name.pop_back();
        }
        add(tid == main_thread                ? sample.io
            : name == WorkerPool::kThreadName ? sample.workers
                                              : sample.other,
            *stat);
        sample.read = true;
    }
    ::closedir(dir);
    return sample;
}

void write_thread_metrics(PrometheusText& out, const ThreadRoleSample& sample) {
    if (!sample.read) {
        return;
    }
    const auto by_role = [&](double SchedStat::*field) {
        return std::vector<std::pair<MetricLabels, double>>{
            {{{"role", "io"}}, sample.io.*field},
            {{{"role", "worker"}}, sample.workers.*field},
            {{{"role", "other"}}, sample.other.*field}};
    };
    out.counter_family("dsoc_thread_cpu_seconds_total",
                       "CPU time of the server's threads by role: io (the I/O thread: sockets, "
                       "the tick's serial parts), worker (the pool: interest and snapshots), "
                       "other (the allocator's and libraries' threads).",
                       by_role(&SchedStat::run_seconds));
    out.counter_family("dsoc_thread_runqueue_wait_seconds_total",
                       "Time the server's threads were ready to run but waited for a core, by "
                       "role (the kernel's schedstat). A large share of the tick period means "
                       "the machine is oversubscribed, not that the server's work grew.",
                       by_role(&SchedStat::wait_seconds));
}

} // namespace dsoc::server
