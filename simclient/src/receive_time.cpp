#include "dsoc/simclient/receive_time.hpp"

#include <linux/sockios.h>
#include <sys/ioctl.h>

#include <ctime>

namespace dsoc::simclient {

namespace {
/// SIOCGSTAMPNS: the socket's last receive timestamp. Its first call on a socket turns
/// timestamps on (and, nothing stamped yet, fails).
bool read_stamp(int fd, timespec& ts) {
    return ::ioctl(fd, SIOCGSTAMPNS, &ts) == 0 && (ts.tv_sec != 0 || ts.tv_nsec != 0);
}
} // namespace

void enable_receive_times(int fd) {
    timespec ts{};
    (void)read_stamp(fd, ts);
}

std::chrono::steady_clock::time_point last_receive_time(int fd) {
    const auto now = std::chrono::steady_clock::now();
    timespec ts{};
    if (!read_stamp(fd, ts)) {
        return now;
    }
    const auto stamp = std::chrono::system_clock::time_point(
        std::chrono::duration_cast<std::chrono::system_clock::duration>(
            std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec)));
    const auto age = std::chrono::system_clock::now() - stamp;
    if (age < std::chrono::system_clock::duration::zero()) {
        return now; // the system clock stepped back since: nothing to measure by
    }
    return now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(age);
}

} // namespace dsoc::simclient
