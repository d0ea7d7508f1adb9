// DatagramBatch: many datagrams to a system call on one socket, and what each one's
// sender learns of its own datagrams.

#include "dsoc/server/datagram_batch.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

namespace {

using dsoc::server::DatagramBatch;

/// A UDP socket on 127.0.0.1, any port; closed at the end of the scope.
struct LoopbackSocket {
    LoopbackSocket() {
        fd = ::socket(AF_INET, SOCK_DGRAM, 0);
        address.sin_family = AF_INET;
        address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
        socklen_t size = sizeof address;
        EXPECT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size), 0);
    }
    ~LoopbackSocket() { ::close(fd); }
    LoopbackSocket(const LoopbackSocket&) = delete;
    LoopbackSocket& operator=(const LoopbackSocket&) = delete;

    /// The datagrams waiting, in order of arrival.
    std::vector<std::vector<std::uint8_t>> received() const {
        std::vector<std::vector<std::uint8_t>> out;
        std::vector<std::uint8_t> buffer(2048);
        for (;;) {
            const ssize_t n = ::recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
            if (n < 0) {
                return out;
            }
            out.emplace_back(buffer.begin(), buffer.begin() + n);
        }
    }

    int fd = -1;
    sockaddr_in address{};
};

TEST(DatagramBatch, MoreDatagramsThanOneCallTakesAllArriveInOrderEachCountedWhole) {
    // Spread over receivers so that each one's buffer, at the kernel's default size,
    // holds its share: loopback delivers while sendmmsg runs.
    LoopbackSocket sender;
    constexpr std::size_t kReceivers = 8;
    std::array<LoopbackSocket, kReceivers> receivers;
    const std::size_t count = DatagramBatch::kMaxPerCall + 300;
    std::vector<std::vector<std::uint8_t>> payloads;
    std::array<std::vector<std::vector<std::uint8_t>>, kReceivers> expected;
    for (std::size_t i = 0; i < count; ++i) {
        payloads.push_back(std::vector<std::uint8_t>(1 + i % 200, static_cast<std::uint8_t>(i)));
        expected[i % kReceivers].push_back(payloads.back());
    }
    DatagramBatch batch;
    for (std::size_t i = 0; i < count; ++i) {
        const LoopbackSocket& to = receivers[i % kReceivers];
        batch.add(sender.fd, payloads[i], reinterpret_cast<const sockaddr*>(&to.address),
                  sizeof to.address);
    }
    ASSERT_EQ(batch.size(), count);
    batch.send();
    for (std::size_t i = 0; i < count; ++i) {
        EXPECT_FALSE(batch.refused(i)) << i;
        EXPECT_EQ(batch.sent_bytes(i), payloads[i].size()) << i;
    }
    for (std::size_t r = 0; r < kReceivers; ++r) {
        EXPECT_EQ(receivers[r].received(), expected[r]) << "receiver " << r;
    }
}

TEST(DatagramBatch, ADatagramTheKernelRefusesIsMarkedAndTheOnesAfterItStillGo) {
    LoopbackSocket sender;
    LoopbackSocket receiver;
    // An IPv6 destination on an IPv4 socket: the kernel refuses that datagram alone.
    sockaddr_in6 wrong_family{};
    wrong_family.sin6_family = AF_INET6;
    wrong_family.sin6_port = receiver.address.sin_port;
    wrong_family.sin6_addr = in6addr_loopback;
    const std::vector<std::uint8_t> a{1, 2, 3};
    const std::vector<std::uint8_t> b{4, 5};
    const std::vector<std::uint8_t> c{6};
    const auto* to = reinterpret_cast<const sockaddr*>(&receiver.address);
    DatagramBatch batch;
    batch.add(sender.fd, b, reinterpret_cast<const sockaddr*>(&wrong_family), sizeof wrong_family);
    batch.add(sender.fd, a, to, sizeof receiver.address);
    batch.add(sender.fd, b, reinterpret_cast<const sockaddr*>(&wrong_family), sizeof wrong_family);
    batch.add(sender.fd, c, to, sizeof receiver.address);
    batch.send();
    EXPECT_TRUE(batch.refused(0));
    EXPECT_EQ(batch.sent_bytes(0), 0u);
    EXPECT_FALSE(batch.refused(1));
    EXPECT_EQ(batch.sent_bytes(1), a.size());
    EXPECT_TRUE(batch.refused(2));
    EXPECT_FALSE(batch.refused(3));
    EXPECT_EQ(batch.sent_bytes(3), c.size());
    EXPECT_EQ(receiver.received(), (std::vector<std::vector<std::uint8_t>>{a, c}));

    // Cleared, the batch is empty and takes another socket's datagrams.
    batch.clear();
    EXPECT_EQ(batch.size(), 0u);
    LoopbackSocket other;
    batch.add(other.fd, c, to, sizeof receiver.address);
    batch.send();
    EXPECT_EQ(batch.sent_bytes(0), c.size());
    EXPECT_EQ(receiver.received(), (std::vector<std::vector<std::uint8_t>>{c}));
}

} // namespace
