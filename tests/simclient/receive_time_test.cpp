#include "dsoc/simclient/receive_time.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <span>
#include <thread>
#include <vector>

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
    std::array<std::uint8_t, 16> buffer{};

    void send() { sender.send_to(asio::buffer(payload), receiver.local_endpoint()); }
    /// Reads the datagram sent (waiting for it up to a second).
    StampedRead read() {
        for (int i = 0; i < 1000; ++i) {
            const StampedRead r = receive_stamped(receiver.native_handle(), buffer);
            if (r.error != EAGAIN) {
                return r;
            }
            std::this_thread::sleep_for(1ms);
        }
        return {};
    }
    /// Turns timestamps on and waits until they come. The kernel turns them on a moment
    /// after the first socket asks (deferred work); until then a datagram carries none and
    /// reads as now. Probes until one comes back stamped before its read.
    bool stamps_on() {
        if (!enable_receive_times(receiver.native_handle())) {
            return false;
        }
        for (int i = 0; i < 200; ++i) {
            send();
            std::this_thread::sleep_for(5ms);
            const StampedRead r = read();
            if (r.bytes != payload.size()) {
                return false; // the probe itself was lost
            }
            if (ms(Clock::now() - r.arrival) >= 4.0) {
                return true;
            }
        }
        return false;
    }
};

// A datagram read well after it arrived is stamped with its arrival, not its reading: the
// difference a busy load generator's own delay makes to its figures.
TEST(ReceiveTime, IsWhenTheDatagramArrivedNotWhenItWasRead) {
    Loopback link;
    ASSERT_TRUE(link.stamps_on()) << "no datagram came with a receive timestamp";

    const auto sent_at = Clock::now();
    link.send();
    std::this_thread::sleep_for(60ms);
    const StampedRead first = link.read();
    ASSERT_EQ(first.bytes, link.payload.size());
    const auto read_at = Clock::now();
    const auto arrived = first.arrival;
    EXPECT_GE(ms(arrived - sent_at), -1.0); // not before the send
    EXPECT_LT(ms(arrived - sent_at), 30.0);
    EXPECT_GE(ms(read_at - arrived), 50.0);

    // Each read gives its own datagram's time, also when both waited to be read.
    std::this_thread::sleep_for(20ms);
    const auto second_sent_at = Clock::now();
    link.send();
    std::this_thread::sleep_for(20ms);
    link.send();
    std::this_thread::sleep_for(20ms);
    const StampedRead second = link.read();
    const StampedRead third = link.read();
    ASSERT_EQ(second.bytes, link.payload.size());
    ASSERT_EQ(third.bytes, link.payload.size());
    EXPECT_GE(ms(second.arrival - second_sent_at), -1.0);
    EXPECT_GE(ms(second.arrival - arrived), 15.0);
    EXPECT_GE(ms(third.arrival - second.arrival), 15.0);
    EXPECT_GE(ms(Clock::now() - third.arrival), 15.0);
    // Nothing left: a read that finds nothing says so and does not wait.
    EXPECT_EQ(receive_stamped(link.receiver.native_handle(), link.buffer).error, EAGAIN);
}

// Without timestamps turned on there is nothing to give but the time of reading.
TEST(ReceiveTime, WithoutTimestampsIsWhenRead) {
    Loopback link;
    link.send();
    std::this_thread::sleep_for(30ms);
    const auto before = Clock::now();
    const StampedRead r = link.read();
    ASSERT_EQ(r.bytes, link.payload.size());
    EXPECT_GE(r.arrival, before);
    EXPECT_LE(ms(r.arrival - before), 1000.0);
}

// Many datagrams to a system call: each into its own buffer with its own size and
// arrival, in the order sent; fewer than asked when no more wait; none, and EAGAIN, after.
TEST(ReceiveTime, ManyToACallEachWithItsOwnBytesAndArrival) {
    Loopback link;
    ASSERT_TRUE(link.stamps_on()) << "no datagram came with a receive timestamp";
    constexpr std::size_t kSent = 5;
    for (std::size_t i = 0; i < kSent; ++i) { // sizes 1..5, each byte its datagram's number
        const std::vector<std::uint8_t> bytes(i + 1, static_cast<std::uint8_t>(i));
        link.sender.send_to(asio::buffer(bytes), link.receiver.local_endpoint());
        std::this_thread::sleep_for(5ms);
    }
    std::array<std::array<std::uint8_t, 16>, 3> buffers{};
    for (auto& b : buffers) {
        b.fill(0xff); // so that a datagram not written into its buffer shows
    }
    std::array<std::span<std::uint8_t>, 3> views{buffers[0], buffers[1], buffers[2]};
    std::array<StampedRead, 3> reads{};
    std::vector<StampedRead> all;
    std::vector<std::size_t> per_call;
    // Until all five are read (a loaded machine may queue one a moment late), then once
    // more: that read finds none.
    for (int call = 0; call < 1000 && all.size() < kSent; ++call) {
        const std::size_t got = receive_stamped(link.receiver.native_handle(), views, reads);
        if (got == 0) {
            std::this_thread::sleep_for(1ms);
            continue;
        }
        per_call.push_back(got);
        for (std::size_t k = 0; k < got; ++k) {
            const std::size_t number = all.size();
            ASSERT_EQ(reads[k].bytes, number + 1) << "datagram " << number;
            for (std::size_t b = 0; b < reads[k].bytes; ++b) {
                EXPECT_EQ(buffers[k][b], number) << "datagram " << number << " byte " << b;
            }
            EXPECT_EQ(reads[k].error, 0);
            all.push_back(reads[k]);
        }
    }
    ASSERT_FALSE(per_call.empty());
    EXPECT_EQ(per_call.front(), 3u); // as many as it asked for: three had waited 10 ms
    EXPECT_EQ(receive_stamped(link.receiver.native_handle(), views, reads), 0u);
    EXPECT_EQ(reads[0].error, EAGAIN);
    ASSERT_EQ(all.size(), kSent);
    for (std::size_t i = 1; i < kSent; ++i) { // sent 5 ms apart: each its own arrival
        EXPECT_GE(ms(all[i].arrival - all[i - 1].arrival), 2.0) << i;
    }
}

} // namespace
} // namespace dsoc::simclient
