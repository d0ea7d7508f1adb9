#pragma once
// Reading a datagram with the time it reached the socket: the kernel's receive timestamp
// (SO_TIMESTAMPNS, carried beside the datagram by recvmsg()), so a load generator sharing
// the server's cores can tell when the server's snapshots arrived from when it got round
// to them, in the one system call that reads the datagram. Linux.
//
// Threading: any; the socket's reader only.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>

namespace dsoc::simclient {

/// Turns receive timestamps on for the datagram socket `fd`: call once, before its first
/// read. False when the socket refuses (every datagram then reads as arriving when read).
bool enable_receive_times(int fd);

/// True when the datagram socket `fd` is shut down for reading (poll()'s POLLRDHUP): it
/// is then reported readable for ever, with nothing to read after what was queued, so a
/// reader woken with nothing to read asks this before waiting again.
[[nodiscard]] bool shut_down_for_reading(int fd);

/// One receive_stamped().
struct StampedRead {
    /// Bytes of the datagram read (a longer one is cut to the buffer's size); 0 with an
    /// error or nothing to read.
    std::size_t bytes = 0;
    /// errno of a failed read: EAGAIN / EWOULDBLOCK when nothing is waiting, ECONNREFUSED
    /// when the host said nothing listens at a connected socket's peer; 0 when one was read.
    int error = 0;
    /// When the kernel received it, on the steady clock (the kernel stamps the system
    /// clock; its distance from the system clock's now is carried over, so a step of the
    /// system clock does not show); when read, where the datagram holds no timestamp
    /// (timestamps off, or turned on a moment after it arrived) or the system clock stepped
    /// back since.
    std::chrono::steady_clock::time_point arrival{};
};

/// Reads the next datagram of `fd` into `buffer` without waiting (MSG_DONTWAIT).
[[nodiscard]] StampedRead receive_stamped(int fd, std::span<std::uint8_t> buffer);

/// The most datagrams one receive_stamped() of many reads.
inline constexpr std::size_t kMaxStampedReads = 16;

/// Reads up to min(buffers.size(), reads.size(), kMaxStampedReads) datagrams of `fd` in
/// one system call (recvmmsg) without waiting, the k-th into buffers[k] and described by
/// reads[k], each with its own arrival. Returns how many it read; 0 when none, with
/// reads[0].error saying why (EAGAIN: none waiting). Fewer than asked means none was left
/// to read at that moment, or an error came after the last one read (the next call
/// reports it).
[[nodiscard]] std::size_t receive_stamped(int fd, std::span<const std::span<std::uint8_t>> buffers,
                                          std::span<StampedRead> reads);

} // namespace dsoc::simclient
