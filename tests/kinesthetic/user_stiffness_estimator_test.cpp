// UserStiffnessEstimator on a one-coordinate finger with known stiffness, damping and mass,
// held by a wall that is eight times stiffer (the closed loop that makes a plain regression
// find the wall), pressing on with a moving intent, its position read through a 1 um
// quantiser. The channel-level test against the virtual user is
// runtime.UserStiffnessEstimate.*.

#include "haptic/kinesthetic/user_stiffness_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "allocation_counter.hpp"

namespace haptic::kinesthetic {
namespace {

constexpr double kDt = 1e-3;
constexpr double kGram = 1e-4;  // |B|^2: k_u = 1e-4 k

struct Finger {
    double k{9000.0};  // N/m along the actuator
    double b{120.0};   // N s/m
    double m{0.2};     // kg
};

struct PressResult {
    double stiffness{std::nan("")};
    double actuator_stiffness{std::nan("")};
    double actuator_damping{std::nan("")};
    double actuator_mass{std::nan("")};
    bool valid{false};
    double largest_probe{0.0};
};

// `seconds` of contact: the wall (k_wall = 8 k, at x = 0) renders u = -k_wall x plus the
// probe moved by `amplitude_m` per tone; the intent presses 1 mm past the wall over 0.3 s
// and then sways by 0.3 mm at 0.7 Hz.
PressResult press(UserStiffnessEstimator& estimator, const Finger& finger, double seconds,
                  double amplitude_m = 50e-6) {
    const double k_wall = 8.0 * finger.k;
    double x = 0.0;
    double v = 0.0;
    double force = 0.0;
    PressResult result;
    for (int i = 0; i < static_cast<int>(seconds / kDt); ++i) {
        const double t = i * kDt;
        const double intent =
            1e-3 * std::min(t / 0.3, 1.0) + 3e-4 * std::sin(2.0 * std::numbers::pi * 0.7 * t);
        const double measured_x = 1e-6 * std::round(x / 1e-6);
        estimator.update(true, force, measured_x, kGram);
        result.largest_probe = std::max(result.largest_probe, std::abs(estimator.probe()));
        force = -k_wall * (measured_x - amplitude_m * estimator.probe());
        // The finger: m x'' = u - k (x - intent) - b x', semi-implicit Euler.
        v += kDt * (force - finger.k * (x - intent) - finger.b * v) / finger.m;
        x += kDt * v;
    }
    result.valid = estimator.valid();
    result.stiffness = estimator.stiffness();
    result.actuator_stiffness = estimator.actuatorStiffness();
    result.actuator_damping = estimator.actuatorDamping();
    result.actuator_mass = estimator.actuatorMass();
    return result;
}

UserStiffnessEstimatorConfig shippedLike() {
    UserStiffnessEstimatorConfig config;
    config.period_s = kDt;
    config.probe_frequency_hz = 5.0;
    config.min_stiffness = 0.03;
    config.max_stiffness = 12.0;
    return config;
}

TEST(UserStiffnessEstimator, FindsTheFingerNotTheWallItPressesOn) {
    for (const double k : {4500.0, 9000.0, 18000.0}) {
        UserStiffnessEstimator estimator(shippedLike());
        const PressResult r = press(estimator, Finger{k, 120.0, 0.2}, 1.5);
        ASSERT_TRUE(r.valid) << k;
        EXPECT_NEAR(r.actuator_stiffness, k, 0.03 * k);
        EXPECT_NEAR(r.stiffness, kGram * k, 0.03 * kGram * k) << "k_u = |B|^2 k";
        EXPECT_NEAR(r.actuator_damping, 120.0, 0.2 * 120.0) << k;
        // The force of a tick is read with the position it produced, a tick later: the
        // damping's phase then reads as a mass of -b dt, which the two tones separate from k
        // like the mass itself (user_stiffness_estimator.hpp). The mass is a by-product
        // (rho* needs k alone) and comes out coarser than k.
        EXPECT_NEAR(r.actuator_mass, 0.2 - 120.0 * kDt, 0.07) << k;
    }
}

TEST(UserStiffnessEstimator, ProbesOnlyInContactAndRestartsWhenItEnds) {
    UserStiffnessEstimator estimator(shippedLike());
    estimator.update(false, 1.0, 0.0, kGram);
    EXPECT_EQ(estimator.probe(), 0.0);
    EXPECT_FALSE(estimator.valid());
    EXPECT_TRUE(std::isnan(estimator.stiffness())) << "no estimate before any contact";
    const PressResult r = press(estimator, Finger{}, 1.0);
    ASSERT_TRUE(r.valid);
    EXPECT_GT(r.largest_probe, 1.0) << "two tones of unit amplitude";
    EXPECT_LE(r.largest_probe, 2.0);
    // Lost for longer than the debounce: the probe ends, the estimate stays.
    for (int i = 0; i < 60; ++i) {
        estimator.update(false, 0.0, 0.0, kGram);
        EXPECT_EQ(estimator.probe(), 0.0);
    }
    EXPECT_FALSE(estimator.valid());
    EXPECT_FALSE(estimator.probing());
    EXPECT_DOUBLE_EQ(estimator.stiffness(), r.stiffness) << "the last estimate is kept";
    // The cooldown: a new contact within a second of the last probe is not probed.
    for (int i = 0; i < 900; ++i) {
        estimator.update(true, 1.0, 0.0, kGram);
        ASSERT_FALSE(estimator.probing()) << i;
    }
    for (int i = 0; i < 100; ++i) {
        estimator.update(true, 1.0, 0.0, kGram);
    }
    EXPECT_TRUE(estimator.probing()) << "probed again after the cooldown";
    EXPECT_FALSE(estimator.valid()) << "a new probe needs a full window again";
}

TEST(UserStiffnessEstimator, ABriefLossOfContactPausesTheProbe) {
    UserStiffnessEstimator estimator(shippedLike());
    const PressResult r = press(estimator, Finger{}, 0.8);
    ASSERT_TRUE(r.valid);
    for (int i = 0; i < 30; ++i) {  // 30 ms, within the 50 ms debounce
        estimator.update(false, 0.0, 0.0, kGram);
        EXPECT_EQ(estimator.probe(), 0.0) << "paused";
    }
    EXPECT_TRUE(estimator.valid());
    estimator.update(true, 0.0, 0.0, kGram);
    EXPECT_TRUE(estimator.probing()) << "and resumed";
}

TEST(UserStiffnessEstimator, TheProbeEndsOnWholePeriodsAndTheEstimateHolds) {
    UserStiffnessEstimatorConfig config = shippedLike();
    config.probe_time_s = 1.45;  // rounded up to 1.6 s: 8 periods of 5 Hz
    UserStiffnessEstimator estimator(config);
    const PressResult r = press(estimator, Finger{}, 1.6 + 1e-4);
    ASSERT_TRUE(r.valid);
    EXPECT_FALSE(estimator.probing());
    EXPECT_EQ(estimator.probe(), 0.0);
    UserStiffnessEstimator longer(config);
    (void)press(longer, Finger{}, 1.599);
    EXPECT_TRUE(longer.probing());
    EXPECT_LT(std::abs(longer.probe()), 0.13) << "the tones end near a common zero";
    const PressResult held = press(estimator, Finger{}, 0.5);  // more contact, no probe
    EXPECT_EQ(held.largest_probe, 0.0);
    EXPECT_DOUBLE_EQ(held.stiffness, r.stiffness);
}

TEST(UserStiffnessEstimator, NonFiniteInputEndsTheContact) {
    UserStiffnessEstimator estimator(shippedLike());
    ASSERT_TRUE(press(estimator, Finger{}, 1.0).valid);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    estimator.update(true, nan, 0.0, kGram);
    EXPECT_FALSE(estimator.valid());
    EXPECT_EQ(estimator.probe(), 0.0);
    ASSERT_TRUE(press(estimator, Finger{}, 2.0).valid) << "after the 1 s cooldown";
    estimator.update(true, 1.0, 0.0, std::numeric_limits<double>::infinity());
    EXPECT_FALSE(estimator.valid());
}

TEST(UserStiffnessEstimator, TheEstimateIsBounded) {
    UserStiffnessEstimatorConfig config = shippedLike();
    config.max_stiffness = 0.5;  // below the finger's 0.9
    UserStiffnessEstimator estimator(config);
    const PressResult r = press(estimator, Finger{}, 1.5);
    ASSERT_TRUE(r.valid);
    EXPECT_DOUBLE_EQ(r.stiffness, 0.5);
    EXPECT_NEAR(r.actuator_stiffness, 9000.0, 0.03 * 9000.0) << "the actuator's k is reported";
}

TEST(UserStiffnessEstimator, NoProbeResponseNoEstimate) {
    // A finger that does not answer the probe (at a joint stop) but moves with the user's
    // intent, 100 um at 1 Hz: nothing at the probe's tones above the threshold.
    UserStiffnessEstimator estimator(shippedLike());
    for (int i = 0; i < 2000; ++i) {
        const double intent_m = 1e-4 * std::sin(2.0 * std::numbers::pi * i * kDt);
        estimator.update(true, 2.0 + 0.1 * estimator.probe() + 9000.0 * intent_m, intent_m, kGram);
    }
    EXPECT_FALSE(estimator.valid());
    EXPECT_LT(estimator.responseAmplitude(), shippedLike().min_response_m);
    EXPECT_GT(estimator.responseAmplitude(), 0.0);
}

TEST(UserStiffnessEstimator, RefusesABadConfigurationNamingTheField) {
    auto reason = [](auto change) -> std::string {
        UserStiffnessEstimatorConfig config = shippedLike();
        change(config);
        try {
            UserStiffnessEstimator estimator(config);
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "accepted";
    };
    EXPECT_NE(reason([](auto& c) { c.probe_frequency_hz = 30.0; }).find("probe_frequency_hz"),
              std::string::npos);
    EXPECT_NE(reason([](auto& c) { c.window_periods = 0.5; }).find("window_periods"),
              std::string::npos);
    EXPECT_NE(reason([](auto& c) { c.max_stiffness = c.min_stiffness; }).find("max_stiffness"),
              std::string::npos);
    EXPECT_NE(reason([](auto& c) { c.period_s = 0.0; }).find("period_s"), std::string::npos);
    EXPECT_NE(reason([](auto& c) { c.probe_time_s = 0.2; }).find("probe_time_s"),
              std::string::npos);
    EXPECT_NE(reason([](auto& c) { c.min_response_m = 0.0; }).find("min_response_m"),
              std::string::npos);
    EXPECT_NE(reason([](auto& c) { c.probe_cooldown_s = -1.0; }).find("probe_cooldown_s"),
              std::string::npos);
    EXPECT_EQ(reason([](auto&) {}), "accepted");
}

TEST(UserStiffnessEstimator, UpdateAllocatesNothing) {
    UserStiffnessEstimator estimator(shippedLike());
    std::uint64_t allocations = 0;
    PressResult r;
    {
        testing::ScopedAllocationCounter counter;
        r = press(estimator, Finger{}, 3.0);  // several rebuilds of the window's sums
        estimator.update(false, 0.0, 0.0, kGram);
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_TRUE(r.valid);
}

}  // namespace
}  // namespace haptic::kinesthetic
