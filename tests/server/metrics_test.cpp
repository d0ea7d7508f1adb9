#include "dsoc/server/heap_stats.hpp"
#include "dsoc/server/metrics.hpp"
#include "dsoc/server/metrics_endpoint.hpp"
#include "dsoc/server/process_metrics.hpp"

#include "support/http_client.hpp"
#include "support/io_thread.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

namespace dsoc::server {
namespace {

using dsoc::testing::http_body;
using dsoc::testing::http_exchange;
using dsoc::testing::http_get;
using dsoc::testing::http_status;
using dsoc::testing::run_on_io_thread;

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

TEST(MetricsEndpoint, AnswersLivenessAndReadiness) {
    boost::asio::io_context io;
    Readiness readiness{false, "loading map 'oa_dm4'"};
    MetricsEndpoint endpoint(
        io, [] { return std::string("dsoc_up 1\n"); }, [&] { return readiness; });
    const std::uint16_t port = endpoint.start("127.0.0.1", 0);
    std::thread thread([&] { io.run(); });

    const auto alive = http_get(port, "/healthz");
    const auto loading = http_get(port, "/readyz");
    run_on_io_thread(io, [&] { readiness = {true, {}}; });
    const auto ready = http_get(port, "/readyz");
    run_on_io_thread(io, [&] { readiness = {false, "shutting down"}; });
    const auto stopping = http_get(port, "/readyz");
    const auto alive_while_stopping = http_get(port, "/healthz");
    const auto post =
        http_exchange(port, "POST /readyz HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n");
    const auto missing = http_get(port, "/health");

    boost::asio::post(io, [&] { endpoint.stop(); });
    thread.join();
    EXPECT_EQ(http_status(alive), 200) << alive;
    EXPECT_EQ(http_body(alive), "ok\n");
    EXPECT_EQ(http_status(loading), 503) << loading;
    EXPECT_EQ(http_body(loading), "not ready: loading map 'oa_dm4'\n");
    EXPECT_EQ(http_status(ready), 200) << ready;
    EXPECT_EQ(http_body(ready), "ready\n");
    EXPECT_EQ(http_status(stopping), 503) << stopping;
    EXPECT_EQ(http_body(stopping), "not ready: shutting down\n");
    EXPECT_EQ(http_status(alive_while_stopping), 200);
    EXPECT_EQ(http_status(post), 405) << post;
    EXPECT_EQ(http_status(missing), 404) << missing;
    EXPECT_EQ(endpoint.requests_served(), 0u); // probes are not scrapes
}

TEST(ProcessMetrics, ReadsThisProcess) {
    const ProcessSample before = read_process_sample();
    std::FILE* file = std::tmpfile();
    ASSERT_NE(file, nullptr);
    const ProcessSample with_file = read_process_sample(true);
    // The allocator's live bytes follow an allocation and its release.
    constexpr double kBlockBytes = 8.0 * 1024 * 1024;
    auto block = std::make_unique<std::vector<std::uint8_t>>(8u << 20, std::uint8_t{1});
    ASSERT_EQ(std::fwrite(block->data(), 1, 1, file), 1u); // the block is used
    const ProcessSample holding = read_process_sample(true);
    block.reset();
    const ProcessSample released = read_process_sample(true);
    std::fclose(file);
    if (running_heap_allocator() != HeapAllocator::unknown) { // a sanitizer's: no figures
        EXPECT_GE(holding.heap_in_use_bytes - with_file.heap_in_use_bytes, kBlockBytes);
        EXPECT_LE(released.heap_in_use_bytes, holding.heap_in_use_bytes - kBlockBytes);
        EXPECT_GE(with_file.heap_free_bytes, 0.0);
    } else {
        EXPECT_LT(holding.heap_in_use_bytes, 0.0) << "no figures are not zeros";
    }
    EXPECT_LT(before.heap_in_use_bytes, 0.0) << "read only when asked";
    const double now =
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();

    EXPECT_GT(before.resident_bytes, 1024.0 * 1024.0);
    EXPECT_GE(before.virtual_bytes, before.resident_bytes);
    EXPECT_GE(before.cpu_seconds, 0.0);
    EXPECT_GE(before.open_fds, 3.0); // stdin, stdout, stderr at least
    EXPECT_EQ(with_file.open_fds, before.open_fds + 1.0);
    EXPECT_GE(before.max_fds, before.open_fds);
    // This test's process started moments ago (ctest runs each test in its own).
    EXPECT_LE(before.start_time_seconds, now + 1.0);
    EXPECT_GT(before.start_time_seconds, now - 600.0);
}

TEST(ProcessMetrics, WritesTheStandardNamesAndBuildInfo) {
    ProcessSample sample;
    sample.cpu_seconds = 1.5;
    sample.resident_bytes = 4096;
    sample.open_fds = 7;
    sample.start_time_seconds = 1700000000;
    sample.heap_in_use_bytes = 8192;
    sample.heap_free_bytes = 512;
    sample.allocator = "jemalloc";
    PrometheusText out;
    write_process_metrics(out, sample);
    write_build_info(out, "0.1.0", "0123456789ab");
    const std::string& t = out.text();
    EXPECT_NE(t.find("# TYPE process_cpu_seconds_total counter\nprocess_cpu_seconds_total 1.5\n"),
              std::string::npos)
        << t;
    EXPECT_NE(t.find("process_resident_memory_bytes 4096\n"), std::string::npos) << t;
    EXPECT_NE(t.find("process_open_fds 7\n"), std::string::npos) << t;
    EXPECT_NE(t.find("process_start_time_seconds 1700000000\n"), std::string::npos) << t;
    EXPECT_NE(t.find("dsoc_heap_in_use_bytes 8192\n"), std::string::npos) << t;
    EXPECT_NE(t.find("dsoc_heap_free_bytes 512\n"), std::string::npos) << t;
    EXPECT_NE(t.find("dsoc_heap_allocator_info{allocator=\"jemalloc\"} 1\n"), std::string::npos)
        << t;
    // Fields that were not read are left out, not written as -1.
    EXPECT_EQ(t.find("process_virtual_memory_bytes"), std::string::npos) << t;
    EXPECT_EQ(t.find("process_max_fds"), std::string::npos) << t;
    EXPECT_NE(t.find("# TYPE dsoc_build_info gauge\n"
                     "dsoc_build_info{version=\"0.1.0\",commit=\"0123456789ab\"} 1\n"),
              std::string::npos)
        << t;
}

} // namespace
} // namespace dsoc::server
