#include "dsoc/simclient/receive_time.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <thread>

namespace dsoc::simclient {
namespace {

namespace asio = boost::asio;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

double ms(Clock::duration d) {
    return std::chrono::duration<double, std::milli>(d).count();
}

struct Loopback {
    asio::io_context io;
    asio::ip::udp::socket receiver{io, {asio::ip::address_v4::loopback(), 0}};
    asio::ip::udp::socket sender{io, {asio::ip::address_v4::loopback(), 0}};
    std::array<char, 4> payload{'p', 'i', 'n', 'g'};
    std::array<char, 16> buffer{};

    void send() { sender.send_to(asio::buffer(payload), receiver.local_endpoint()); }
    std::size_t read() { return receiver.receive(asio::buffer(buffer)); }
};

// A datagram read well after it arrived is stamped with its arrival, not its reading: the
// difference a busy load generator's own delay makes to its figures.
TEST(ReceiveTime, IsWhenTheDatagramArrivedNotWhenItWasRead) {
    Loopback link;
    enable_receive_times(link.receiver.native_handle());
    // The kernel turns its receive timestamps on a moment after the first socket asks
    // (deferred work); until then a datagram carries none and reads as now. Probe until
    // one comes back stamped before its read.
    bool stamped = false;
    for (int i = 0; i < 200 && !stamped; ++i) {
        link.send();
        std::this_thread::sleep_for(5ms);
        ASSERT_EQ(link.read(), link.payload.size());
        stamped = ms(Clock::now() - last_receive_time(link.receiver.native_handle())) >= 4.0;
    }
    ASSERT_TRUE(stamped) << "no datagram came with a receive timestamp";

    const auto sent_at = Clock::now();
    link.send();
    std::this_thread::sleep_for(60ms);
    ASSERT_EQ(link.read(), link.payload.size());
    const auto read_at = Clock::now();
    const auto arrived = last_receive_time(link.receiver.native_handle());
    EXPECT_GE(ms(arrived - sent_at), -1.0); // not before the send
    EXPECT_LT(ms(arrived - sent_at), 30.0);
    EXPECT_GE(ms(read_at - arrived), 50.0);

    // Each read gives its own datagram's time.
    std::this_thread::sleep_for(20ms);
    const auto second_sent_at = Clock::now();
    link.send();
    ASSERT_EQ(link.read(), link.payload.size());
    const auto second = last_receive_time(link.receiver.native_handle());
    EXPECT_GE(ms(second - second_sent_at), -1.0);
    EXPECT_GE(ms(second - arrived), 15.0);
}

// Without timestamps turned on there is nothing to give but the time of asking.
TEST(ReceiveTime, WithoutTimestampsIsNow) {
    Loopback link;
    const auto before = Clock::now();
    const auto t = last_receive_time(link.receiver.native_handle());
    EXPECT_GE(t, before);
    EXPECT_LE(ms(t - before), 1000.0);
}

} // namespace
} // namespace dsoc::simclient
