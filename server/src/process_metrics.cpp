#include "dsoc/server/process_metrics.hpp"

#include "dsoc/server/heap_stats.hpp"

#include <dirent.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace dsoc::server {

namespace {

double seconds(const timeval& t) {
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
}

/// Entries of /proc/self/fd, less the one the listing itself holds open.
double count_open_fds() {
    DIR* dir = ::opendir("/proc/self/fd");
    if (dir == nullptr) {
        return -1.0;
    }
    const int own = ::dirfd(dir);
    double count = 0.0;
    while (const dirent* entry = ::readdir(dir)) {
        const std::string name = entry->d_name;
        if (name != "." && name != ".." && name != std::to_string(own)) {
            count += 1.0;
        }
    }
    ::closedir(dir);
    return count;
}

/// btime of /proc/stat: when the machine booted, Unix time [s]; -1 if unread.
double boot_time_seconds() {
    std::ifstream proc_stat("/proc/stat");
    std::string key;
    while (proc_stat >> key) {
        if (key == "btime") {
            double boot_time = -1.0;
            proc_stat >> boot_time;
            return boot_time;
        }
        proc_stat.ignore(1 << 20, '\n');
    }
    return -1.0;
}

/// Field 22 of /proc/self/stat, the start in clock ticks after boot, plus the boot time.
double start_time_seconds() {
    std::ifstream stat_file("/proc/self/stat");
    std::string stat;
    std::getline(stat_file, stat);
    // The command name (field 2) is in parentheses and may hold spaces: count after it.
    const auto close = stat.rfind(')');
    if (close == std::string::npos) {
        return -1.0;
    }
    std::istringstream fields(stat.substr(close + 1));
    std::string field;
    for (int i = 3; i <= 22; ++i) {
        if (!(fields >> field)) {
            return -1.0;
        }
    }
    const double boot_time = boot_time_seconds();
    const long ticks_per_second = ::sysconf(_SC_CLK_TCK);
    if (boot_time < 0.0 || ticks_per_second <= 0) {
        return -1.0;
    }
    char* end = nullptr;
    const double ticks = std::strtod(field.c_str(), &end);
    if (end == field.c_str() || *end != '\0') {
        return -1.0;
    }
    return boot_time + ticks / static_cast<double>(ticks_per_second);
}

} // namespace

ProcessSample read_process_sample(bool costly_heap) {
    ProcessSample s;
    if (rusage usage{}; ::getrusage(RUSAGE_SELF, &usage) == 0) {
        s.cpu_seconds = seconds(usage.ru_utime) + seconds(usage.ru_stime);
    }
    // /proc/self/statm: sizes in pages, total (virtual) then resident.
    std::ifstream statm("/proc/self/statm");
    double virtual_pages = 0.0;
    double resident_pages = 0.0;
    if (const long page = ::sysconf(_SC_PAGESIZE);
        page > 0 && statm >> virtual_pages >> resident_pages) {
        s.virtual_bytes = virtual_pages * static_cast<double>(page);
        s.resident_bytes = resident_pages * static_cast<double>(page);
    }
    s.open_fds = count_open_fds();
    if (rlimit limit{};
        ::getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
        s.max_fds = static_cast<double>(limit.rlim_cur);
    }
    s.start_time_seconds = start_time_seconds();
    const HeapAllocator allocator = running_heap_allocator();
    s.allocator = allocator_name(allocator);
    if (const auto heap = read_heap_sample(costly_heap)) {
        s.heap_in_use_bytes = heap->in_use_bytes;
        s.heap_free_bytes = heap->free_bytes;
    }
    return s;
}

void write_process_metrics(PrometheusText& out, const ProcessSample& s) {
    if (s.cpu_seconds >= 0.0) {
        out.counter("process_cpu_seconds_total", "Total user and system CPU time spent in seconds.",
                    s.cpu_seconds);
    }
    if (s.resident_bytes >= 0.0) {
        out.gauge("process_resident_memory_bytes", "Resident memory size in bytes.",
                  s.resident_bytes);
    }
    if (s.virtual_bytes >= 0.0) {
        out.gauge("process_virtual_memory_bytes", "Virtual memory size in bytes.", s.virtual_bytes);
    }
    if (s.open_fds >= 0.0) {
        out.gauge("process_open_fds", "Number of open file descriptors.", s.open_fds);
    }
    if (s.max_fds >= 0.0) {
        out.gauge("process_max_fds", "Maximum number of open file descriptors.", s.max_fds);
    }
    if (s.start_time_seconds >= 0.0) {
        out.gauge("process_start_time_seconds",
                  "Start time of the process since unix epoch in seconds.", s.start_time_seconds);
    }
    if (!s.allocator.empty()) {
        out.gauge("dsoc_heap_allocator_info", "The C allocator the server runs on. Always 1.",
                  {{"allocator", std::string(s.allocator)}}, 1.0);
    }
    if (s.heap_in_use_bytes >= 0.0) {
        out.gauge("dsoc_heap_in_use_bytes", "Bytes of the C allocator's live allocations.",
                  s.heap_in_use_bytes);
    }
    if (s.heap_free_bytes >= 0.0) {
        out.gauge("dsoc_heap_free_bytes",
                  "Bytes the C allocator holds beyond its live allocations: memory the server "
                  "freed, resident until the allocator gives it back to the system.",
                  s.heap_free_bytes);
    }
}

void write_build_info(PrometheusText& out, std::string_view version, std::string_view commit) {
    out.gauge("dsoc_build_info",
              "The dsoc-server build that runs: version and git commit (empty when unknown). "
              "Always 1.",
              {{"version", std::string(version)}, {"commit", std::string(commit)}}, 1.0);
}

} // namespace dsoc::server
