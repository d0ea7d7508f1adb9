#pragma once
// Datagrams of several clients' snapshots handed to the kernel in as few system calls as
// it takes (sendmmsg, up to kMaxPerCall to a call), all on one socket. Each system call
// costs about what a small datagram's trip through loopback does, so the hand-over writes
// many clients' snapshots to a call rather than one client's (Connection::queue_now()).
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
    /// Appends a datagram of `bytes` (which must stay valid until send()) to `peer` on
    /// `socket` (every datagram of a batch goes on the same socket); returns its index.
    std::size_t add(int socket, std::span<const std::uint8_t> bytes, const sockaddr* peer,
                    socklen_t peer_size);
    [[nodiscard]] std::size_t size() const { return messages_.size(); }
    /// Hands every datagram to the kernel without blocking. One it refuses (its buffer
    /// full) is marked refused and the ones after it still go, as with a call each.
    void send();
    /// After send(): the bytes the kernel took of datagram `index`; 0 when refused.
    [[nodiscard]] std::size_t sent(std::size_t index) const {
        return refused_[index] != 0 ? 0 : messages_[index].msg_len;
    }
    [[nodiscard]] bool refused(std::size_t index) const { return refused_[index] != 0; }

private:
    int socket_ = -1;
    std::vector<mmsghdr> messages_;
    std::vector<iovec> parts_;
    std::vector<std::uint8_t> refused_;
};

} // namespace dsoc::server
