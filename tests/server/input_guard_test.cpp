#include "dsoc/server/input_guard.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace dsoc::server {
namespace {

namespace pb = protocol::pb;
using Clock = InputRateLimiter::Clock;
using Decision = InputRateLimiter::Decision;

TEST(SanitizeInput, InRangeInputIsUntouched) {
    pb::ClientInput in;
    in.set_move_x(0.6f);
    in.set_move_y(-0.8f);
    in.set_view_yaw(-180.0f);
    in.set_view_pitch(90.0f);
    const auto before = in.SerializeAsString();
    const auto verdict = sanitize_input(in);
    EXPECT_TRUE(verdict.usable);
    EXPECT_EQ(verdict.clamped_fields, 0);
    EXPECT_EQ(in.SerializeAsString(), before);
}

TEST(SanitizeInput, OutOfRangeValuesAreClamped) {
    pb::ClientInput in;
    in.set_move_x(3.0e38f); // the squared length overflows a float
    in.set_move_y(3.0e38f);
    in.set_view_yaw(540.0f);
    in.set_view_pitch(-100.0f);
    const auto verdict = sanitize_input(in);
    EXPECT_TRUE(verdict.usable);
    EXPECT_EQ(verdict.clamped_fields, 2); // the yaw is wrapped, which is not clamping
    EXPECT_NEAR(std::hypot(in.move_x(), in.move_y()), 1.0f, 1e-6f);
    EXPECT_NEAR(in.move_x(), std::sqrt(0.5f), 1e-6f);
    EXPECT_FLOAT_EQ(in.view_yaw(), -180.0f); // 540 = 180 (mod 360) -> [-180, 180)
    EXPECT_FLOAT_EQ(in.view_pitch(), -90.0f);
}

TEST(SanitizeInput, YawWrapsIntoHalfOpenRange) {
    for (const float yaw : {180.0f, 359.0f, -181.0f, 1.0e9f, -1.0e9f, 3.0e38f}) {
        pb::ClientInput in;
        in.set_view_yaw(yaw);
        ASSERT_TRUE(sanitize_input(in).usable);
        EXPECT_GE(in.view_yaw(), -180.0f) << yaw;
        EXPECT_LT(in.view_yaw(), 180.0f) << yaw;
        // The same angle: equal modulo 360 (fmod and remainder are exact).
        const double expected = std::fmod(static_cast<double>(yaw), 360.0);
        EXPECT_NEAR(std::remainder(static_cast<double>(in.view_yaw()) - expected, 360.0), 0.0, 1e-9)
            << yaw;
    }
}

TEST(SanitizeInput, NonFiniteValuesMakeTheInputUnusable) {
    const float bad[] = {std::numeric_limits<float>::quiet_NaN(),
                         std::numeric_limits<float>::infinity(),
                         -std::numeric_limits<float>::infinity()};
    for (const float v : bad) {
        pb::ClientInput a;
        a.set_move_z(v);
        const auto va = sanitize_input(a);
        EXPECT_FALSE(va.usable);
        EXPECT_EQ(va.why, "client_input.move_z is not a finite number");
        pb::ClientInput b;
        b.set_view_pitch(v);
        EXPECT_FALSE(sanitize_input(b).usable);
    }
}

TEST(InputRateLimiter, BurstOfOneSecondThenTheCap) {
    const auto t0 = Clock::time_point{} + std::chrono::hours(1);
    InputRateLimiter limiter(30, t0);
    for (int i = 0; i < 30; ++i) {
        EXPECT_EQ(limiter.on_message(t0), Decision::accept) << i;
    }
    EXPECT_EQ(limiter.on_message(t0), Decision::drop);
    // Steady at exactly the cap: every message is accepted.
    auto t = t0;
    for (int i = 0; i < 300; ++i) {
        t += std::chrono::microseconds(1'000'000 / 30 + 1);
        EXPECT_EQ(limiter.on_message(t), Decision::accept) << i;
    }
    EXPECT_EQ(limiter.dropped(), 1u);
}

TEST(InputRateLimiter, OverTheCapIsDroppedDownToTheCapWithoutFlood) {
    const auto t0 = Clock::time_point{} + std::chrono::hours(1);
    InputRateLimiter limiter(30, t0);
    auto t = t0;
    int accepted = 0;
    for (int i = 0; i < 550; ++i) { // 55/s (under twice the cap) for 10 s
        t += std::chrono::microseconds(1'000'000 / 55);
        const auto d = limiter.on_message(t);
        ASSERT_NE(d, Decision::flood) << i;
        accepted += d == Decision::accept ? 1 : 0;
    }
    EXPECT_NEAR(accepted, 30 + 300, 3); // the burst, then the cap
    EXPECT_EQ(limiter.dropped(), 550u - static_cast<unsigned>(accepted));
}

TEST(InputRateLimiter, MoreThanTwiceTheCapWithinASecondIsAFlood) {
    const auto t0 = Clock::time_point{} + std::chrono::hours(1);
    InputRateLimiter limiter(30, t0);
    int i = 0;
    Decision d = Decision::accept;
    for (; i < 1000 && d != Decision::flood; ++i) {
        d = limiter.on_message(t0 + std::chrono::milliseconds(i));
    }
    EXPECT_EQ(d, Decision::flood);
    EXPECT_EQ(limiter.dropped(), 31u); // 30 drops are tolerated within the second
    EXPECT_LT(i, 70);
}

} // namespace
} // namespace dsoc::server
