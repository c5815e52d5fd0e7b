#include "haptic/kinesthetic/constraint_blend.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace haptic::kinesthetic {
namespace {

msgs::LinearConstraint wall(double b, double angle_rad = 0.0) {
    msgs::LinearConstraint c;
    c.a = {-std::cos(angle_rad), -std::sin(angle_rad), 0.0};
    c.b = b;
    return c;
}

// Feeds `set` for `ticks` ticks (a sim frame held between arrivals); returns the b of the first
// constraint rendered on each tick.
std::vector<double> hold(ConstraintBlend& sut, const std::vector<msgs::LinearConstraint>& set,
                         int ticks) {
    std::vector<double> rendered;
    for (int i = 0; i < ticks; ++i) {
        const auto out = sut.update(set);
        EXPECT_EQ(out.size(), set.size());
        rendered.push_back(out.empty() ? 0.0 : out[0].b);
    }
    return rendered;
}

// The sim's frames every 10 ticks: once the interval is known, a contact that moves is approached
// in ten equal steps from where it was rendered, and reached on the tenth.
TEST(ConstraintBlend, AMovingContactIsApproachedOverTheIntervalBetweenFrames) {
    ConstraintBlend sut;
    EXPECT_DOUBLE_EQ(hold(sut, {wall(0.10)}, 10).front(), 0.10) << "the first set as it comes";
    (void)hold(sut, {wall(0.20)}, 10);  // learns the interval
    (void)hold(sut, {wall(0.30)}, 10);
    EXPECT_EQ(sut.rampTicks(), 10);
    const auto ramp = hold(sut, {wall(0.40)}, 10);
    for (int i = 0; i < 10; ++i) {
        EXPECT_NEAR(ramp[static_cast<std::size_t>(i)], 0.30 + 0.01 * (i + 1), 1e-12) << i;
    }
    // A frame that comes early restarts the ramp from where it stands: no step.
    const auto early = hold(sut, {wall(0.50)}, 3);
    const auto next = hold(sut, {wall(0.30)}, 1);
    EXPECT_NEAR(early.back(), 0.43, 1e-12);
    EXPECT_LT(std::abs(next.front() - early.back()), 0.05);
}

TEST(ConstraintBlend, ANewOrLostContactOrATurnedNormalIsRenderedAtOnce) {
    ConstraintBlend sut;
    (void)hold(sut, {wall(0.10)}, 10);
    (void)hold(sut, {wall(0.20)}, 10);
    // A second contact appears: both at once.
    auto out = sut.update(std::vector{wall(0.30), wall(0.05, 1.0)});
    ASSERT_EQ(out.size(), 2U);
    EXPECT_DOUBLE_EQ(out[0].b, 0.30);
    EXPECT_DOUBLE_EQ(out[1].b, 0.05);
    // The normal turns by 60 degrees (cosine 0.5): another contact, at once.
    out = sut.update(std::vector{wall(0.30, 1.0472), wall(0.05, 1.0)});
    EXPECT_DOUBLE_EQ(out[0].b, 0.30);
    EXPECT_DOUBLE_EQ(out[0].a[1], -std::sin(1.0472));
    // Contact lost: nothing to render, at once.
    EXPECT_TRUE(sut.update({}).empty());
}

TEST(ConstraintBlend, ARampNeverOutlastsItsBoundAndResetForgetsIt) {
    ConstraintBlend sut;
    (void)hold(sut, {wall(0.0)}, 200);
    (void)hold(sut, {wall(1.0)}, 200);  // one frame every 200 ticks
    EXPECT_EQ(sut.rampTicks(), ConstraintBlend::kMaxRampTicks);
    const auto ramp = hold(sut, {wall(2.0)}, ConstraintBlend::kMaxRampTicks);
    EXPECT_DOUBLE_EQ(ramp.back(), 2.0);
    sut.reset();
    EXPECT_DOUBLE_EQ(sut.update(std::vector{wall(5.0)})[0].b, 5.0);
}

}  // namespace
}  // namespace haptic::kinesthetic
