// The One Euro filter on tracked hand poses (tracking_filter.hpp), with the parameters
// sim.yaml documents: it must take a tracker's jitter out of a hand at rest and follow a
// moving hand with a bounded lag.

#include "haptic/softhand/tracking_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace haptic::softhand {
namespace {

constexpr double kTrackerRateHz = 90.0;  // config/user.yaml's tracker
constexpr double kAngleNoiseRad = 0.002;
constexpr double kPositionNoiseM = 0.0002;

// sim.yaml's tracking_filter values, the angle channel on (angle_beta_s_per_rad: 10) as
// shipped; the key is optional, and without it only the wrist position is filtered.
TrackingFilterSettings settingsWithAngles() {
    return {OneEuroParameters{2.0, 10.0, 1.0}, {2.0, 50.0, 1.0}};
}

double rms(const std::vector<double>& values) {
    double sum = 0.0;
    for (const double v : values) {
        sum += v * v;
    }
    return std::sqrt(sum / static_cast<double>(values.size()));
}

TEST(TrackingFilter, AHandAtRestLosesMostOfTheTrackersJitter) {
    HandPoseFilter filter(settingsWithAngles());
    std::mt19937 random(7);
    std::normal_distribution<double> angle_noise(0.0, kAngleNoiseRad);
    std::normal_distribution<double> position_noise(0.0, kPositionNoiseM);
    HandPoseInput rest;
    rest.flexion_rad.fill(0.3);
    rest.wrist.position_m = Vec3(0.1, 0.0, 0.05);
    std::vector<double> angle_error;
    std::vector<double> position_error;
    std::vector<double> orientation_error;
    for (int i = 0; i < 900; ++i) {  // 10 s
        HandPoseInput noisy = rest;
        for (double& angle : noisy.flexion_rad) {
            angle += angle_noise(random);
        }
        for (int axis = 0; axis < 3; ++axis) {
            noisy.wrist.position_m[axis] += position_noise(random);
        }
        const Vec3 tilt(angle_noise(random), angle_noise(random), angle_noise(random));
        noisy.wrist.rotation = Eigen::AngleAxisd(tilt.norm(), tilt.normalized()).toRotationMatrix();
        const HandPoseInput out = filter.filter(noisy, i / kTrackerRateHz, 0.1);
        if (i < 90) {
            continue;  // settling
        }
        angle_error.push_back(out.flexion_rad[4] - 0.3);
        position_error.push_back(out.wrist.position_m.x() - 0.1);
        orientation_error.push_back(
            Eigen::Quaterniond(out.wrist.rotation).angularDistance(Eigen::Quaterniond::Identity()));
        EXPECT_NEAR(out.wrist.rotation.determinant(), 1.0, 1e-9);
    }
    std::printf(
        "at rest: angle jitter %.2e rad (tracker %.1e), position %.2e m (tracker %.1e), "
        "orientation %.2e rad\n",
        rms(angle_error), kAngleNoiseRad, rms(position_error), kPositionNoiseM,
        rms(orientation_error));
    EXPECT_LT(rms(angle_error), 0.35 * kAngleNoiseRad);
    EXPECT_LT(rms(position_error), 0.35 * kPositionNoiseM);
    // The raw orientation's error is |tilt|: sqrt(3) sigma RMS.
    EXPECT_LT(rms(orientation_error), 0.35 * std::sqrt(3.0) * kAngleNoiseRad);
}

// A flexion at 1 rad/s, the speed of a quick press, and a wrist sliding at 0.1 m/s: the
// filtered pose trails the true one by a bounded time once the motion is under way.
TEST(TrackingFilter, AMovingHandIsFollowedWithABoundedLag) {
    HandPoseFilter filter(settingsWithAngles());
    HandPoseInput pose;
    double angle_lag_s = 0.0;
    double position_lag_s = 0.0;
    for (int i = 0; i < 45; ++i) {  // 0.5 s
        const double t = i / kTrackerRateHz;
        pose.flexion_rad.fill(1.0 * t);
        pose.wrist.position_m = Vec3(0.1 * t, 0.0, 0.0);
        const HandPoseInput out = filter.filter(pose, t, 0.1);
        angle_lag_s = (pose.flexion_rad[0] - out.flexion_rad[0]) / 1.0;
        position_lag_s = (pose.wrist.position_m.x() - out.wrist.position_m.x()) / 0.1;
    }
    std::printf("in motion: angle lag %.1f ms at 1 rad/s, wrist lag %.1f ms at 0.1 m/s\n",
                angle_lag_s * 1e3, position_lag_s * 1e3);
    EXPECT_LT(angle_lag_s, 0.030);
    EXPECT_LT(position_lag_s, 0.030);
}

// Each parameter of sim.yaml's tracking_filter acts: the lag behind a ramp of the angles and
// of the wrist, after 0.3 s, shrinks as min_cutoff or a beta rises, and the derivative
// cutoff sets how soon the beta's rise arrives.
TEST(TrackingFilter, EveryParameterChangesTheLag) {
    auto lags = [](const TrackingFilterSettings& settings) {
        HandPoseFilter filter(settings);
        HandPoseInput pose;
        std::pair<double, double> lag;
        for (int i = 0; i < 27; ++i) {
            const double t = i / kTrackerRateHz;
            pose.flexion_rad.fill(1.0 * t);
            pose.wrist.position_m = Vec3(0.1 * t, 0.0, 0.0);
            const HandPoseInput out = filter.filter(pose, t, 0.1);
            lag = {pose.flexion_rad[0] - out.flexion_rad[0],
                   pose.wrist.position_m.x() - out.wrist.position_m.x()};
        }
        return lag;
    };
    const TrackingFilterSettings base = settingsWithAngles();
    const auto [angle_lag, position_lag] = lags(base);
    TrackingFilterSettings faster = base;
    faster.angles->min_cutoff_hz *= 2.0;
    faster.position.min_cutoff_hz *= 2.0;
    EXPECT_LT(lags(faster).first, angle_lag);
    EXPECT_LT(lags(faster).second, position_lag);
    TrackingFilterSettings angle_beta = base;
    angle_beta.angles->beta *= 2.0;
    EXPECT_LT(lags(angle_beta).first, angle_lag);
    EXPECT_EQ(lags(angle_beta).second, position_lag);
    TrackingFilterSettings position_beta = base;
    position_beta.position.beta *= 2.0;
    EXPECT_EQ(lags(position_beta).first, angle_lag);
    EXPECT_LT(lags(position_beta).second, position_lag);
    TrackingFilterSettings slow_derivative = base;
    slow_derivative.angles->derivative_cutoff_hz *= 0.25;
    slow_derivative.position.derivative_cutoff_hz *= 0.25;
    EXPECT_GT(lags(slow_derivative).first, angle_lag);
    EXPECT_GT(lags(slow_derivative).second, position_lag);
}

// Without angle_beta_s_per_rad (an optional key; sim.yaml ships it): the wrist position is
// filtered as before, the angles and the wrist's orientation reach the hand exactly as
// tracked.
TEST(TrackingFilter, WithoutTheAngleChannelOnlyTheWristPositionIsFiltered) {
    TrackingFilterSettings settings = settingsWithAngles();
    settings.angles.reset();
    HandPoseFilter position_only(settings);
    HandPoseFilter both(settingsWithAngles());
    std::mt19937 random(3);
    std::normal_distribution<double> noise(0.0, kAngleNoiseRad);
    for (int i = 0; i < 90; ++i) {
        HandPoseInput noisy;
        for (double& angle : noisy.flexion_rad) {
            angle = 0.3 + noise(random);
        }
        noisy.wrist.position_m = Vec3(0.1 + 0.1 * noise(random), 0.0, 0.05);
        const Vec3 tilt(noise(random), noise(random), noise(random));
        noisy.wrist.rotation = Eigen::AngleAxisd(tilt.norm(), tilt.normalized()).toRotationMatrix();
        const double t = i / kTrackerRateHz;
        const HandPoseInput out = position_only.filter(noisy, t, 0.1);
        const HandPoseInput reference = both.filter(noisy, t, 0.1);
        EXPECT_EQ(out.flexion_rad, noisy.flexion_rad) << i;
        EXPECT_TRUE(out.wrist.rotation.isApprox(noisy.wrist.rotation, 1e-12)) << i;
        EXPECT_EQ(out.wrist.position_m, reference.wrist.position_m) << i;
        if (i > 0) {
            EXPECT_NE(out.wrist.position_m.x(), noisy.wrist.position_m.x()) << i;
        }
    }
}

TEST(TrackingFilter, AGapOrAStampThatGoesBackRestartsAtTheNewPose) {
    HandPoseFilter filter(settingsWithAngles());
    HandPoseInput a;
    a.flexion_rad.fill(0.0);
    HandPoseInput jitter = a;
    jitter.flexion_rad.fill(kAngleNoiseRad);
    HandPoseInput b;
    b.flexion_rad.fill(1.0);
    b.wrist.position_m = Vec3(0.05, 0.0, 0.0);
    (void)filter.filter(a, 0.0, 0.1);
    (void)filter.filter(a, 0.011, 0.1);
    EXPECT_LT(filter.filter(jitter, 0.022, 0.1).flexion_rad[0], 0.2 * kAngleNoiseRad)
        << "a jitter-sized step is smoothed";
    // Tracking resumed after a silence longer than the timeout: no slow glide from the old pose.
    EXPECT_EQ(filter.filter(b, 0.5, 0.1).flexion_rad[0], 1.0);
    EXPECT_EQ(filter.filter(a, 0.4, 0.1).flexion_rad[0], 0.0) << "a stamp that went back";
    EXPECT_EQ(filter.filter(a, 0.4, 0.1).wrist.position_m.x(), 0.0);
}

}  // namespace
}  // namespace haptic::softhand
