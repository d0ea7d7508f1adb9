#include "dsoc/simclient/udp_link.hpp"

#include "dsoc/simclient/scenario.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <gtest/gtest.h>

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
    protocol::pb::Envelope hello;
    hello.mutable_client_hello()->set_protocol_version(1);
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

} // namespace
} // namespace dsoc::simclient
