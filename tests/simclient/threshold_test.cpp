// Thresholds: parsing (figures, operators, units) and evaluation against a report.

#include "dsoc/simclient/load_report.hpp"
#include "dsoc/simclient/quantity.hpp"
#include "dsoc/simclient/report_figures.hpp"
#include "dsoc/simclient/threshold.hpp"

#include <gtest/gtest.h>

namespace dsoc::simclient {
namespace {

Threshold parsed(const std::string& text) {
    Threshold t;
    std::string error;
    EXPECT_TRUE(parse_threshold(text, t, error)) << text << ": " << error;
    return t;
}

std::string parse_error(const std::string& text) {
    Threshold t;
    std::string error;
    EXPECT_FALSE(parse_threshold(text, t, error)) << text;
    return error;
}

TEST(Threshold, ParsesFigureOperatorAndUnits) {
    const Threshold ms = parsed("interarrival_p99<50ms");
    EXPECT_EQ(ms.figure, "interarrival_p99");
    EXPECT_EQ(ms.comparison, Comparison::less);
    EXPECT_DOUBLE_EQ(ms.limit.base, 50.0);
    EXPECT_EQ(ms.limit.unit, "ms");

    const Threshold s = parsed(" rtt_p95 <= 0.25 s ");
    EXPECT_EQ(s.comparison, Comparison::less_equal);
    EXPECT_DOUBLE_EQ(s.limit.base, 250.0);
    EXPECT_EQ(s.text, "rtt_p95<=0.25s");

    const Threshold rate = parsed("bytes_down_per_client>=1.5KiB/s");
    EXPECT_EQ(rate.comparison, Comparison::greater_equal);
    EXPECT_DOUBLE_EQ(rate.limit.base, 1536.0);
    EXPECT_DOUBLE_EQ(parsed("bytes_up_per_client<2MB/s").limit.base, 2e6);

    const Threshold percent = parsed("failure_rate<1%");
    EXPECT_DOUBLE_EQ(percent.limit.base, 0.01);
    EXPECT_DOUBLE_EQ(parsed("failure_rate<0.01").limit.base, 0.01);

    const Threshold count = parsed("connected>5");
    EXPECT_EQ(count.comparison, Comparison::greater);
    EXPECT_DOUBLE_EQ(count.limit.base, 5.0);
    // A bare time is in the base unit, milliseconds.
    EXPECT_DOUBLE_EQ(parsed("connect_time_p99<20").limit.base, 20.0);
}

TEST(Threshold, AnUnknownFigureNamesTheKnownOnes) {
    const std::string error = parse_error("latency_p99<50ms");
    EXPECT_NE(error.find("unknown figure 'latency_p99'"), std::string::npos) << error;
    EXPECT_NE(error.find("known: " + figure_names()), std::string::npos) << error;
    EXPECT_NE(figure_names().find("interarrival_p99"), std::string::npos);
}

TEST(Threshold, RefusesBadOperatorsUnitsAndNumbers) {
    EXPECT_NE(parse_error("interarrival_p99 50ms").find("expected FIGURE OP VALUE"),
              std::string::npos);
    EXPECT_NE(parse_error("interarrival_p99==50ms").find("unknown operator"), std::string::npos);
    EXPECT_NE(parse_error("interarrival_p99<<50ms").find("unknown operator"), std::string::npos);
    EXPECT_NE(parse_error("interarrival_p99<50KiB/s").find("does not fit; expected a time"),
              std::string::npos);
    EXPECT_NE(parse_error("interarrival_p99<50parsecs").find("unknown unit 'parsecs'"),
              std::string::npos);
    EXPECT_NE(parse_error("connected>5ms").find("expected a bare number"), std::string::npos);
    EXPECT_NE(parse_error("interarrival_p99<fast").find("is not a number"), std::string::npos);
    EXPECT_NE(parse_error("<50ms").find("expected FIGURE OP VALUE"), std::string::npos);
}

TEST(Threshold, EvaluatesAgainstTheReportInTheLimitsUnit) {
    LoadReport report;
    report.snapshot_interarrival_ms.count = 100;
    report.snapshot_interarrival_ms.p99 = 61.25;
    report.connected = 8;
    report.connect_failures = 2;
    report.failures = 2;
    const auto results =
        evaluate_thresholds({parsed("interarrival_p99<50ms"), parsed("interarrival_p99<0.1s"),
                             parsed("failure_rate<=20%"), parsed("failure_rate<10%"),
                             parsed("connected>=8"), parsed("rtt_p99<10ms")},
                            report);
    ASSERT_EQ(results.size(), 6u);
    EXPECT_FALSE(results[0].passed);
    EXPECT_EQ(describe(results[0]), "interarrival_p99 < 50ms: observed 61.25 ms");
    EXPECT_TRUE(results[1].passed);
    EXPECT_EQ(describe(results[1]), "interarrival_p99 < 0.1s: observed 0.06125 s");
    EXPECT_TRUE(results[2].passed); // 2 of 10 sessions: 20%
    EXPECT_FALSE(results[3].passed);
    EXPECT_EQ(describe(results[3]), "failure_rate < 10%: observed 20 %");
    EXPECT_TRUE(results[4].passed);
    // No pong, no round trip: nothing shows the threshold holds.
    EXPECT_FALSE(results[5].passed);
    EXPECT_FALSE(results[5].has_value);
    EXPECT_EQ(describe(results[5]), "rtt_p99 < 10ms: no samples");

    report.thresholds = {results[1], results[2]};
    report.connected = 10;
    report.connect_failures = 0;
    report.failures = 0;
    EXPECT_TRUE(report.passed());
    report.thresholds.push_back(results[0]);
    EXPECT_FALSE(report.passed());
}

TEST(Threshold, EntityFiguresAreAbsentWhenNoClientDecodedAndPresentOnceOneDid) {
    // With LoadConfig::check_every, a run may decode no snapshot at all: its entity
    // figures are then absent (a threshold on them cannot pass on a 0 it never measured).
    LoadReport r;
    for (const char* name : {"entities_known_mean", "entities_known_p95", "entities_heard_mean"}) {
        const Figure* f = find_figure(name);
        ASSERT_NE(f, nullptr) << name;
        EXPECT_FALSE(f->read(r).present) << name;
    }
    r.entities_known.count = 3;
    r.entities_known.mean = 12.5;
    const FigureValue known = find_figure("entities_known_mean")->read(r);
    EXPECT_TRUE(known.present);
    EXPECT_DOUBLE_EQ(known.value, 12.5);
    EXPECT_FALSE(find_figure("entities_heard_mean")->read(r).present);
}

TEST(Quantity, DurationsAreSecondsAndMayBeCompound) {
    double s = 0.0;
    std::string error;
    ASSERT_TRUE(parse_duration_s("1m30s", s, error)) << error;
    EXPECT_DOUBLE_EQ(s, 90.0);
    ASSERT_TRUE(parse_duration_s("250ms", s, error)) << error;
    EXPECT_DOUBLE_EQ(s, 0.25);
    ASSERT_TRUE(parse_duration_s("12", s, error)) << error;
    EXPECT_DOUBLE_EQ(s, 12.0);
    EXPECT_FALSE(parse_duration_s("-1s", s, error));
    EXPECT_FALSE(parse_duration_s("1m30", s, error));
    EXPECT_NE(error.find("without a unit"), std::string::npos) << error;
    Quantity q;
    EXPECT_FALSE(parse_quantity("1KiB/s2B/s", Dimension::byte_rate, q, error));
    EXPECT_NE(error.find("only times may be compound"), std::string::npos) << error;
}

} // namespace
} // namespace dsoc::simclient
