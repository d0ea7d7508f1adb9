#pragma once
// Datagrams of several clients' snapshots handed to the kernel in as few system calls as
// it takes: sendmmsg, up to kMaxPerCall datagrams to a call, one call per run of
// datagrams on the same socket (the server has one UDP socket: one run).
//
// Threading: one thread's at a time (a pool thread fills, sends and reads back its own).

#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::server {

class DatagramBatch {
public:
    /// Most datagrams to one sendmmsg call (the kernel's UIO_MAXIOV).
    static constexpr std::size_t kMaxPerCall = 1024;

    /// Forgets every datagram, keeping the memory.
    void clear();
    /// Appends a datagram of `bytes` to `peer` on `socket`; `bytes` and `peer` must stay
    /// valid until send(). Returns its index.
    std::size_t add(int socket, std::span<const std::uint8_t> bytes, const sockaddr* peer,
                    socklen_t peer_size);
    [[nodiscard]] std::size_t size() const { return messages_.size(); }
    /// Hands every datagram to the kernel without blocking. One the kernel refuses, for
    /// whatever reason (a full buffer, a bad address), is marked refused and the ones
    /// after it still go, as with a call each.
    void send();
    /// After send(): the bytes the kernel took of datagram `index` (0: refused).
    [[nodiscard]] std::size_t sent_bytes(std::size_t index) const {
        return refused_[index] != 0 ? 0 : messages_[index].msg_len;
    }
    [[nodiscard]] bool refused(std::size_t index) const { return refused_[index] != 0; }

private:
    std::vector<int> sockets_;
    std::vector<mmsghdr> messages_;
    std::vector<iovec> parts_;
    std::vector<std::uint8_t> refused_;
};

} // namespace dsoc::server
