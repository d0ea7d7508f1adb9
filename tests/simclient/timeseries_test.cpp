// The time series line and the progress line of one second.

#include "dsoc/simclient/timeseries.hpp"

#include <gtest/gtest.h>

namespace dsoc::simclient {
namespace {

TEST(Timeseries, OneJsonLinePerSecondWithRatesOverTheInterval) {
    SecondSample s;
    s.t_s = 3.0004;
    s.interval_s = 0.5;
    s.target = 10;
    s.connected = 9;
    s.connecting = 1;
    s.snapshots = 150;
    s.bytes_down = 5120;
    s.bytes_up = 1000;
    s.interarrival_ms.count = 150;
    s.interarrival_ms.p50 = 33.33;
    s.interarrival_ms.p99 = 41.06;
    s.failures = {{"refused", 2}};
    s.failures_total = 3;
    EXPECT_EQ(format_timeseries_line(s),
              R"({"t_s":3.0,"target":10,"connected":9,"connecting":1,"snapshots_per_s":300.0,)"
              R"("bytes_down_per_s":10240.0,"bytes_up_per_s":2000.0,"interarrival_p50_ms":33.3,)"
              R"("interarrival_p99_ms":41.1,"failures":{"refused":2},"failures_total":3,)"
              R"("protocol_errors_total":0})");
    EXPECT_EQ(format_progress_line(s),
              "[  3.0s] clients 9/10 connected, 1 connecting | snapshots/s 300 | down 10.0 KiB/s "
              "| up 2.0 KiB/s | failures 3 (this second: refused=2) | protocol errors 0");

    SecondSample empty;
    empty.t_s = 1.0;
    empty.interval_s = 1.0;
    const std::string line = format_timeseries_line(empty);
    EXPECT_NE(line.find(R"("interarrival_p50_ms":null)"), std::string::npos) << line;
    EXPECT_NE(line.find(R"("failures":{})"), std::string::npos) << line;
}

} // namespace
} // namespace dsoc::simclient
