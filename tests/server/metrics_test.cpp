#include "dsoc/server/metrics.hpp"
#include "dsoc/server/metrics_endpoint.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <gtest/gtest.h>

#include <thread>

namespace dsoc::server {
namespace {

TEST(DurationHistogram, BucketsAreCumulativeAndUpperInclusive) {
    DurationHistogram h;
    h.observe(0.0001); // exactly the first bound: in it
    h.observe(0.0002);
    h.observe(0.02);
    h.observe(5.0); // beyond the last bound: +Inf only
    h.observe(std::nan(""));
    EXPECT_EQ(h.count(), 5u);
    EXPECT_EQ(h.cumulative(0), 2u); // 0.0001 and NaN (as 0)
    EXPECT_EQ(h.cumulative(1), 3u);
    EXPECT_EQ(h.cumulative(7), 4u); // le 0.02
    EXPECT_EQ(h.cumulative(DurationHistogram::kBounds.size() - 1), 4u);
    EXPECT_EQ(h.cumulative(DurationHistogram::kBounds.size()), 5u);
    EXPECT_NEAR(h.sum(), 5.0203, 1e-9);
}

TEST(PrometheusText, WritesTheExpositionFormat) {
    PrometheusText out;
    out.counter("dsoc_bytes_sent_total", "Bytes sent.", 1234);
    out.gauge("dsoc_clients", "Clients\nnow.", 3);
    out.counter_family("dsoc_disconnects_total", "By reason.",
                       {{{{"reason", "too_slow"}}, 2}, {{{"reason", "a\"b\\c"}}, 1}});
    DurationHistogram h;
    h.observe(0.003);
    out.histogram("dsoc_tick_duration_seconds", "Tick.", h);
    const std::string& t = out.text();
    EXPECT_NE(t.find("# HELP dsoc_bytes_sent_total Bytes sent.\n"
                     "# TYPE dsoc_bytes_sent_total counter\n"
                     "dsoc_bytes_sent_total 1234\n"),
              std::string::npos)
        << t;
    EXPECT_NE(t.find("# HELP dsoc_clients Clients\\nnow.\n"), std::string::npos) << t;
    EXPECT_NE(t.find("dsoc_disconnects_total{reason=\"too_slow\"} 2\n"), std::string::npos) << t;
    EXPECT_NE(t.find("dsoc_disconnects_total{reason=\"a\\\"b\\\\c\"} 1\n"), std::string::npos) << t;
    EXPECT_NE(t.find("dsoc_tick_duration_seconds_bucket{le=\"0.0025\"} 0\n"), std::string::npos)
        << t;
    EXPECT_NE(t.find("dsoc_tick_duration_seconds_bucket{le=\"0.005\"} 1\n"), std::string::npos)
        << t;
    EXPECT_NE(t.find("dsoc_tick_duration_seconds_bucket{le=\"+Inf\"} 1\n"
                     "dsoc_tick_duration_seconds_sum 0.003\n"
                     "dsoc_tick_duration_seconds_count 1\n"),
              std::string::npos)
        << t;
    EXPECT_EQ(t.back(), '\n');
}

/// Sends `request` to 127.0.0.1:port and returns the whole response.
std::string http_exchange(std::uint16_t port, const std::string& request) {
    boost::asio::io_context io;
    boost::asio::ip::tcp::socket socket(io);
    socket.connect({boost::asio::ip::make_address("127.0.0.1"), port});
    boost::asio::write(socket, boost::asio::buffer(request));
    std::string response;
    boost::system::error_code ec;
    boost::asio::read(socket, boost::asio::dynamic_buffer(response), ec);
    return response;
}

TEST(MetricsEndpoint, ServesMetricsAndNothingElse) {
    boost::asio::io_context io;
    int renders = 0;
    MetricsEndpoint endpoint(io, [&] {
        ++renders;
        return std::string("dsoc_up 1\n");
    });
    const std::uint16_t port = endpoint.start("127.0.0.1", 0);
    std::thread thread([&] { io.run(); });

    const auto ok = http_exchange(port, "GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n");
    const auto missing = http_exchange(port, "GET /other HTTP/1.1\r\nHost: x\r\n\r\n");
    const auto post =
        http_exchange(port, "POST /metrics HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n");
    const auto garbage = http_exchange(port, "\x01\x02 not http\r\n\r\n");

    boost::asio::post(io, [&] { endpoint.stop(); });
    thread.join();
    EXPECT_EQ(ok.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << ok;
    EXPECT_NE(ok.find("Content-Type: text/plain; version=0.0.4"), std::string::npos) << ok;
    EXPECT_EQ(ok.substr(ok.size() - 10), "dsoc_up 1\n") << ok;
    EXPECT_EQ(missing.rfind("HTTP/1.1 404", 0), 0u) << missing;
    EXPECT_EQ(post.rfind("HTTP/1.1 405", 0), 0u) << post;
    EXPECT_TRUE(garbage.empty()) << garbage; // not HTTP: the connection is just closed
    EXPECT_EQ(renders, 1);
    EXPECT_EQ(endpoint.requests_served(), 1u);
}

} // namespace
} // namespace dsoc::server
