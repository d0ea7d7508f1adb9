#include "dsoc/simclient/receive_time.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

namespace dsoc::simclient {

bool enable_receive_times(int fd) {
    const int on = 1;
    return ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) == 0;
}

bool shut_down_for_reading(int fd) {
    pollfd p{fd, static_cast<short>(POLLIN | POLLRDHUP), 0};
    return ::poll(&p, 1, 0) == 1 && (p.revents & POLLRDHUP) != 0;
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

/// The arrival of the datagram `message` holds (its SCM_TIMESTAMPNS, if any), read at `now`.
std::chrono::steady_clock::time_point arrival_of(msghdr& message,
                                                 std::chrono::steady_clock::time_point now) {
    timespec stamp{};
    for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS &&
            c->cmsg_len >= CMSG_LEN(sizeof stamp)) {
            std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
        }
    }
    return on_steady_clock(stamp, now);
}

} // namespace

StampedRead receive_stamped(int fd, std::span<std::uint8_t> buffer) {
    StampedRead read;
    const std::span<std::uint8_t> one[1] = {buffer};
    (void)receive_stamped(fd, one, std::span(&read, 1));
    return read;
}

std::size_t receive_stamped(int fd, std::span<const std::span<std::uint8_t>> buffers,
                            std::span<StampedRead> reads) {
    const std::size_t n = std::min({buffers.size(), reads.size(), kMaxStampedReads});
    if (n == 0) {
        return 0;
    }
    // Only the first n entries are set (and read): no call pays for all of them.
    std::array<mmsghdr, kMaxStampedReads> messages;
    std::array<iovec, kMaxStampedReads> parts;
    struct alignas(cmsghdr) Control {
        char bytes[CMSG_SPACE(sizeof(timespec))];
    };
    std::array<Control, kMaxStampedReads> controls;
    for (std::size_t k = 0; k < n; ++k) {
        parts[k] = {buffers[k].data(), buffers[k].size()};
        messages[k] = {};
        msghdr& h = messages[k].msg_hdr;
        h.msg_iov = &parts[k];
        h.msg_iovlen = 1;
        h.msg_control = controls[k].bytes;
        h.msg_controllen = sizeof controls[k].bytes;
    }
    const int got =
        ::recvmmsg(fd, messages.data(), static_cast<unsigned>(n), MSG_DONTWAIT, nullptr);
    const auto now = std::chrono::steady_clock::now();
    if (got <= 0) {
        reads[0] = {};
        reads[0].error = got < 0 ? errno : EAGAIN;
        return 0;
    }
    for (std::size_t k = 0; k < static_cast<std::size_t>(got); ++k) {
        // Without MSG_TRUNC msg_len is what the buffer holds.
        reads[k].bytes = std::min<std::size_t>(messages[k].msg_len, buffers[k].size());
        reads[k].error = 0;
        reads[k].arrival = arrival_of(messages[k].msg_hdr, now);
    }
    return static_cast<std::size_t>(got);
}

} // namespace dsoc::simclient
