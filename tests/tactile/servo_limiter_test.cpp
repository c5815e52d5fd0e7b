#include "haptic/tactile/servo_limiter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace haptic::tactile {
namespace {

config::ServoConfig servos() {
    config::ServoConfig s;
    s.min_rad = -0.5;
    s.max_rad = 1.5;
    s.max_rate_rad_per_s = 7.0;
    return s;
}

TEST(ServoLimiterTest, JumpsBecomeRampsAtTheRateLimit) {
    ServoLimiter sut(servos(), {0.0, 0.0, 0.0});
    const auto first = sut.step({1.0, -0.001, 0.0}, 0.001);
    EXPECT_TRUE(first.rate_limited);
    EXPECT_DOUBLE_EQ(first.servo_rad[0], 0.007);
    EXPECT_DOUBLE_EQ(first.servo_rad[1], -0.001);
    int ticks = 1;
    while (sut.step({1.0, -0.001, 0.0}, 0.001).rate_limited) {
        ++ticks;
    }
    EXPECT_EQ(ticks, 142);  // 142 full 7 mrad steps, the 143rd arrives at 1 rad
    EXPECT_DOUBLE_EQ(sut.last()[0], 1.0);
}

TEST(ServoLimiterTest, TargetsOutsideTheRangeAreClamped) {
    ServoLimiter sut(servos(), {1.499, -0.499, 0.0});  // within one rate step of the ends
    const auto out = sut.step({3.0, -3.0, 0.0}, 0.001);
    EXPECT_TRUE(out.range_clamped);
    EXPECT_DOUBLE_EQ(out.servo_rad[0], 1.5);
    EXPECT_DOUBLE_EQ(out.servo_rad[1], -0.5);
}

TEST(ServoLimiterTest, NonFiniteTargetsHoldThePreviousCommand) {
    ServoLimiter sut(servos(), {0.2, 0.3, 0.4});
    const auto out = sut.step({std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}, 0.001);
    EXPECT_TRUE(out.rejected);
    EXPECT_DOUBLE_EQ(out.servo_rad[0], 0.2);
    EXPECT_TRUE(sut.step({0.0, 0.0, 0.0}, std::numeric_limits<double>::infinity()).rejected);
    EXPECT_DOUBLE_EQ(sut.last()[2], 0.4);
}

}  // namespace
}  // namespace haptic::tactile
