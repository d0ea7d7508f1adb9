#include "dsoc/simclient/receive_time.hpp"

#include <sys/socket.h>
#include <sys/uio.h>

#include <cerrno>
#include <cstring>
#include <ctime>

namespace dsoc::simclient {

bool enable_receive_times(int fd) {
    const int on = 1;
    return ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) == 0;
}

namespace {

/// `stamp` (the system clock) on the steady clock, as far before `now` as it is before the
/// system clock's now; `now` when the stamp is empty or in the future.
std::chrono::steady_clock::time_point on_steady_clock(const timespec& stamp,
                                                      std::chrono::steady_clock::time_point now) {
    if (stamp.tv_sec == 0 && stamp.tv_nsec == 0) {
        return now;
    }
    const auto system = std::chrono::system_clock::time_point(
        std::chrono::duration_cast<std::chrono::system_clock::duration>(
            std::chrono::seconds(stamp.tv_sec) + std::chrono::nanoseconds(stamp.tv_nsec)));
    const auto age = std::chrono::system_clock::now() - system;
    if (age < std::chrono::system_clock::duration::zero()) {
        return now; // the system clock stepped back since: nothing to measure by
    }
    return now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(age);
}

} // namespace

StampedRead receive_stamped(int fd, std::span<std::uint8_t> buffer) {
    iovec io{buffer.data(), buffer.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
    msghdr message{};
    message.msg_iov = &io;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof control;
    StampedRead read;
    const ssize_t n = ::recvmsg(fd, &message, MSG_DONTWAIT);
    const auto now = std::chrono::steady_clock::now();
    if (n < 0) {
        read.error = errno;
        return read;
    }
    read.bytes = static_cast<std::size_t>(n);
    timespec stamp{};
    for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS &&
            c->cmsg_len >= CMSG_LEN(sizeof stamp)) {
            std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
        }
    }
    read.arrival = on_steady_clock(stamp, now);
    return read;
}

} // namespace dsoc::simclient
