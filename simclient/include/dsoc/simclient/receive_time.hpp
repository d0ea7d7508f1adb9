#pragma once
// When a datagram reached a client's socket: the kernel's receive timestamp, so a load
// generator sharing the server's cores can tell when the server's snapshots arrived
// from when it got round to them. Linux (SIOCGSTAMPNS).
//
// Threading: any; the socket's reader only (the timestamp is of its last read).

#include <chrono>

namespace dsoc::simclient {

/// Turns timestamps on for the datagram socket `fd`: call once, before its first read.
void enable_receive_times(int fd);

/// When the kernel received the datagram last read from `fd`, on the steady clock (the
/// kernel stamps the system clock; its distance from the system clock's now is carried
/// over, so a step of the system clock between reads does not show); now, when it holds
/// no timestamp (not enabled, nothing read since, not a datagram socket, or read in the
/// moment before the kernel, asked by the first socket, turned them on).
[[nodiscard]] std::chrono::steady_clock::time_point last_receive_time(int fd);

} // namespace dsoc::simclient
