#include "dsoc/simclient/udp_link.hpp"

#include "dsoc/simclient/scenario.hpp"

#include <arpa/inet.h>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <time.h>

#include <array>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace dsoc::simclient {
namespace {

namespace asio = boost::asio;

// What owns a link in the load generator (a SimClient): the link dies with it.
struct Owner {
    std::unique_ptr<UdpLink> link;
};

/// The hello a link sends (its content is not what these tests look at).
protocol::pb::Envelope a_hello() {
    protocol::pb::Envelope hello;
    hello.mutable_client_hello()->set_protocol_version(1);
    return hello;
}

// The link's receive wait lasts until its socket closes, so it holds its owner weakly.
// Closing queues that wait's completion (aborted); when the owner is freed before the
// io_context runs it (its last strong hold was elsewhere), the completion must not read
// the freed link. This fails under the sanitizer build (scripts/test --sanitize) with a
// heap-use-after-free when the handler looks at the link before seeing that its owner
// is gone.
TEST(UdpLink, AWaitCompletedAfterItsOwnerIsFreedTouchesNothing) {
    asio::io_context io;
    asio::ip::udp::socket server(io, {asio::ip::address_v4::loopback(), 0});
    auto owner = std::make_shared<Owner>();
    std::weak_ptr<Owner> watch = owner;
    owner->link = std::make_unique<UdpLink>(io, UdpLink::Handlers{}, DatagramFaults{}, 1);
    const protocol::pb::Envelope hello = a_hello();
    std::string error;
    ASSERT_TRUE(owner->link->connect({server.local_endpoint()}, hello, owner, error)) << error;
    owner->link->close();
    owner.reset(); // the retry timer's aborted wait still holds it; the receive wait does not
    EXPECT_FALSE(watch.expired());
    io.run(); // the timer's completion frees the owner and the link, then the receive's runs
    EXPECT_TRUE(watch.expired());
    // The request was sent before the close: the link did connect and send.
    std::array<std::uint8_t, 2048> got{};
    asio::ip::udp::endpoint from;
    server.non_blocking(true);
    boost::system::error_code ec;
    const std::size_t n = server.receive_from(asio::buffer(got), from, 0, ec);
    EXPECT_FALSE(ec) << ec.message();
    EXPECT_GT(n, 0u);
}

// A name may resolve to addresses this host cannot send to (an IPv6 address without
// IPv6, say): connect() goes on to the next, as a TCP connect does, and only when none
// opens does it fail, naming each. Here the broadcast address, which a socket without
// SO_BROADCAST may not connect to (EACCES), stands before the server's.
TEST(UdpLink, AnAddressThatCannotBeOpenedIsPassedOverForTheNext) {
    asio::io_context io;
    asio::ip::udp::socket server(io, {asio::ip::address_v4::loopback(), 0});
    const asio::ip::udp::endpoint unusable(asio::ip::address_v4::broadcast(), 9);
    const protocol::pb::Envelope hello = a_hello();
    std::string error;
    auto owner = std::make_shared<Owner>();
    owner->link = std::make_unique<UdpLink>(io, UdpLink::Handlers{}, DatagramFaults{}, 1);
    ASSERT_TRUE(owner->link->connect({unusable, server.local_endpoint()}, hello, owner, error))
        << error;
    io.run_for(std::chrono::milliseconds(50));
    std::array<std::uint8_t, 2048> got{};
    asio::ip::udp::endpoint from;
    server.non_blocking(true);
    boost::system::error_code ec;
    EXPECT_GT(server.receive_from(asio::buffer(got), from, 0, ec), 0u) << ec.message();
    owner->link->close();

    auto alone = std::make_shared<Owner>();
    alone->link = std::make_unique<UdpLink>(io, UdpLink::Handlers{}, DatagramFaults{}, 2);
    const asio::ip::udp::endpoint also_unusable(asio::ip::address_v4::broadcast(), 10);
    EXPECT_FALSE(alone->link->connect({unusable, also_unusable}, hello, alone, error));
    EXPECT_NE(error.find("255.255.255.255"), std::string::npos) << error;
    EXPECT_NE(error.find("; "), std::string::npos) << "both addresses named: " << error;
    alone->link->close();
}

/// Two distinct loopback UDP ports nothing listens on (bound together, then closed): a
/// datagram sent there comes back as ICMP port unreachable.
std::array<asio::ip::udp::endpoint, 2> closed_ports(asio::io_context& io) {
    asio::ip::udp::socket a(io, {asio::ip::address_v4::loopback(), 0});
    asio::ip::udp::socket b(io, {asio::ip::address_v4::loopback(), 0});
    return {a.local_endpoint(), b.local_endpoint()}; // closed when `a` and `b` go
}

// When the host says nothing listens at any address, the owner hears once what became
// of each one tried, in order: refused, could not be opened, refused. The link stays
// open (the owner decides): the handshake's retries to the last address, refused again,
// are not reported again.
TEST(UdpLink, ARefusalNamesEveryAddressTriedOnce) {
    asio::io_context io;
    const auto [first, last] = closed_ports(io);
    const asio::ip::udp::endpoint unusable(asio::ip::address_v4::broadcast(), 9);
    int refusals = 0;
    std::string why;
    UdpLink::Handlers handlers;
    handlers.on_refused = [&](const std::string& w) {
        ++refusals;
        why = w;
    };
    auto owner = std::make_shared<Owner>();
    owner->link = std::make_unique<UdpLink>(io, std::move(handlers), DatagramFaults{}, 1);
    const protocol::pb::Envelope hello = a_hello();
    std::string error;
    ASSERT_TRUE(owner->link->connect({first, unusable, last}, hello, owner, error)) << error;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (refusals == 0 && std::chrono::steady_clock::now() < deadline) {
        io.run_for(std::chrono::milliseconds(10));
    }
    io.run_for(std::chrono::milliseconds(600)); // two handshake retries, each refused
    owner->link->close();
    ASSERT_EQ(refusals, 1);
    const auto at_first = why.find("127.0.0.1:" + std::to_string(first.port()) + ": ");
    const auto at_unusable = why.find("255.255.255.255:9: cannot open");
    const auto at_last = why.find("127.0.0.1:" + std::to_string(last.port()) + ": ");
    ASSERT_NE(at_first, std::string::npos) << why;
    ASSERT_NE(at_unusable, std::string::npos) << why;
    ASSERT_NE(at_last, std::string::npos) << why;
    EXPECT_LT(at_first, at_unusable) << why;
    EXPECT_LT(at_unusable, at_last) << why;
    EXPECT_NE(why.find("refused", at_first), std::string::npos) << why;
    EXPECT_NE(why.find("refused", at_last), std::string::npos) << why;
}

/// The descriptor of the socket connected to `server` (the link's; the test's server
/// socket is bound, not connected): the test reaches under the link to break its socket
/// as the kernel might. -1 when none.
int socket_towards(const asio::ip::udp::endpoint& server) {
    for (int fd = 3; fd < 4096; ++fd) {
        sockaddr_in peer{};
        socklen_t size = sizeof peer;
        if (::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &size) == 0 &&
            peer.sin_family == AF_INET && ntohs(peer.sin_port) == server.port() &&
            ntohl(peer.sin_addr.s_addr) == server.address().to_v4().to_uint()) {
            return fd;
        }
    }
    return -1;
}

/// CPU time this thread has used.
std::chrono::nanoseconds thread_cpu() {
    timespec t{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return std::chrono::seconds(t.tv_sec) + std::chrono::nanoseconds(t.tv_nsec);
}

// A socket the kernel will never give another datagram (here shut down for reading: a
// read returns at once with nothing) must end the link's reading, reported once to its
// owner, not be read again and again: a spinning link would take a core from the
// load generator and the server it measures.
TEST(UdpLink, ASocketThatCanNoLongerBeReadIsGivenUpNotPolled) {
    asio::io_context io;
    asio::ip::udp::socket server(io, {asio::ip::address_v4::loopback(), 0});
    auto owner = std::make_shared<Owner>();
    int failures = 0;
    std::string failure;
    UdpLink::Handlers handlers;
    handlers.on_socket_error = [&](const std::string& why) {
        ++failures;
        failure = why;
    };
    owner->link = std::make_unique<UdpLink>(io, std::move(handlers), DatagramFaults{}, 1);
    const protocol::pb::Envelope hello = a_hello();
    std::string error;
    ASSERT_TRUE(owner->link->connect({server.local_endpoint()}, hello, owner, error)) << error;
    const int fd = socket_towards(server.local_endpoint());
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::shutdown(fd, SHUT_RD), 0);
    const auto cpu_before = thread_cpu();
    io.run_for(std::chrono::milliseconds(300));
    const auto cpu = thread_cpu() - cpu_before;
    EXPECT_LT(cpu, std::chrono::milliseconds(100)) << "the link kept reading a dead socket";
    EXPECT_EQ(failures, 1);
    EXPECT_NE(failure.find("can no longer be read"), std::string::npos) << failure;
    owner->link->close();
}

} // namespace
} // namespace dsoc::simclient
