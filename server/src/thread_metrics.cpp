#include "dsoc/server/thread_metrics.hpp"

#include "dsoc/common/read_file.hpp"
#include "dsoc/server/worker_pool.hpp"

#include <dirent.h>
#include <sys/types.h>
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

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

std::atomic<pid_t> io_thread{0}; // mark_io_thread()'s; 0: none marked

enum class Role : std::uint8_t { io, worker, other };

/// The file's text; "" when it cannot be read (a thread that ended meanwhile).
std::string text_of(const std::string& path) {
    std::string text;
    (void)common::read_file(path, text);
    return text;
}

void add(SchedStat& to, const SchedStat& s) {
    to.run_seconds += s.run_seconds;
    to.wait_seconds += s.wait_seconds;
    to.timeslices += s.timeslices;
}

SchedStat& of_role(ThreadRoleSample& sample, Role role) {
    return role == Role::io ? sample.io : (role == Role::worker ? sample.workers : sample.other);
}

/// What read_thread_roles() keeps between calls: every live thread's last reading, and
/// the sums of those that ended.
struct Meter {
    struct Seen {
        Role role = Role::other;
        SchedStat last;
        bool alive = false; ///< found by the current listing
    };
    std::mutex mutex;
    std::unordered_map<pid_t, Seen> threads;
    ThreadRoleSample ended;
};

} // namespace

void mark_io_thread() {
    io_thread.store(::gettid());
}

ThreadRoleSample read_thread_roles() {
    static Meter meter;
    const std::lock_guard lock(meter.mutex);
    const std::unique_ptr<DIR, int (*)(DIR*)> dir(::opendir("/proc/self/task"), &::closedir);
    if (dir == nullptr) {
        return {};
    }
    for (auto& [tid, seen] : meter.threads) {
        seen.alive = false;
    }
    const pid_t io = io_thread.load();
    bool ran = false;
    while (const dirent* entry = ::readdir(dir.get())) {
        const std::string name = entry->d_name;
        if (name == "." || name == "..") {
            continue;
        }
        const std::string task = "/proc/self/task/" + name;
        const auto stat = parse_schedstat(text_of(task + "/schedstat"));
        if (!stat) {
            continue; // ended meanwhile, or a kernel without schedstat
        }
        std::string comm = text_of(task + "/comm");
        if (!comm.empty() && comm.back() == '\n') {
            comm.pop_back();
        }
        pid_t tid = 0;
        if (std::from_chars(name.data(), name.data() + name.size(), tid).ec != std::errc()) {
            continue;
        }
        Meter::Seen& seen = meter.threads[tid];
        seen.role = tid == io                         ? Role::io
                    : comm == WorkerPool::kThreadName ? Role::worker
                                                      : Role::other;
        seen.last = *stat;
        seen.alive = true;
        ran = ran || stat->run_seconds > 0.0;
    }
    ThreadRoleSample sample = meter.ended;
    for (auto it = meter.threads.begin(); it != meter.threads.end();) {
        if (it->second.alive) {
            add(of_role(sample, it->second.role), it->second.last);
            ++it;
        } else { // ended: what it had counts on
            add(of_role(meter.ended, it->second.role), it->second.last);
            add(of_role(sample, it->second.role), it->second.last);
            it = meter.threads.erase(it);
        }
    }
    sample.read = ran; // a kernel that keeps no schedstat reads 0 for every thread
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
                       "CPU time of the server's threads by role: io (the thread serving the "
                       "sockets, which also runs the tick's serial parts and a share of its "
                       "moves and writes), worker (the pool: interest, snapshots, moves, "
                       "writes), other (the allocator's background threads, a bake's at "
                       "start-up, libnats', a world process's tick loop).",
                       by_role(&SchedStat::run_seconds));
    out.counter_family("dsoc_thread_runqueue_wait_seconds_total",
                       "Time the server's threads were ready to run but waited for a core, by "
                       "role (the kernel's schedstat). A large share of the tick period means "
                       "the machine is oversubscribed, not that the server's work grew.",
                       by_role(&SchedStat::wait_seconds));
}

} // namespace dsoc::server
