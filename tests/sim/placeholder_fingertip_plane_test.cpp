#include "haptic/sim/placeholder_fingertip_plane.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace haptic::sim {
namespace {

using ::testing::DoubleNear;
using ::testing::Eq;

class PlaceholderFingertipPlaneTest : public ::testing::Test {
  protected:
    PlaceholderFingerParameters parameters;
    PlaceholderFingertipPlane sut{parameters};
};

TEST_F(PlaceholderFingertipPlaneTest, DistanceGradientMatchesFiniteDifferences) {
    sut.setJointAngles(Eigen::Vector3d(0.3, 0.5, 0.2));
    const Eigen::Vector3d analytic = sut.distanceGradient();
    constexpr double kStep = 1e-7;
    for (int j = 0; j < 3; ++j) {
        Eigen::Vector3d q(0.3, 0.5, 0.2);
        q[j] += kStep;
        sut.setJointAngles(q);
        const double plus = sut.fingertipDistance();
        q[j] -= 2 * kStep;
        sut.setJointAngles(q);
        const double minus = sut.fingertipDistance();
        EXPECT_THAT(analytic[j], DoubleNear((plus - minus) / (2 * kStep), 1e-7)) << "joint " << j;
    }
}

TEST_F(PlaceholderFingertipPlaneTest, ScriptedPressIndentsThePlaneByThePressDepth) {
    sut.setTime(0.0);
    EXPECT_GT(sut.fingertipDistance(), 0.0) << "at rest the finger is clear of the plane";
    sut.setTime(0.5 * parameters.press_period_s);
    EXPECT_THAT(sut.fingertipDistance(), DoubleNear(-parameters.press_depth_m, 1e-12));
}

TEST_F(PlaceholderFingertipPlaneTest, ConstraintSetProjectsOutOfThePlaneAndIsLinearisedAtQ) {
    sut.setTime(0.5 * parameters.press_period_s);
    msgs::ConstraintSet message;
    sut.fillConstraintSet(message);
    ASSERT_THAT(message.dof, Eq(3));
    ASSERT_THAT(message.constraints.size(), Eq(1U));
    const auto& c = message.constraints[0];
    const Eigen::Vector3d a(c.a[0], c.a[1], c.a[2]);
    const Eigen::Vector3d q_sim(message.q_sim_rad[0], message.q_sim_rad[1], message.q_sim_rad[2]);
    // The tracked configuration violates the constraint; the projected one sits on it.
    EXPECT_LT(a.dot(sut.jointAngles()), c.b);
    EXPECT_THAT(a.dot(q_sim), DoubleNear(c.b, 1e-12));
    // And to first order the projected fingertip is on the plane.
    sut.setJointAngles(q_sim);
    EXPECT_THAT(sut.fingertipDistance(), DoubleNear(0.0, 2e-4));
}

TEST_F(PlaceholderFingertipPlaneTest, NoConstraintWhileFarFromThePlane) {
    sut.setTime(0.0);
    msgs::ConstraintSet message;
    sut.fillConstraintSet(message);
    EXPECT_TRUE(message.constraints.empty());
    EXPECT_THAT(message.q_sim_rad[0], Eq(sut.jointAngles()[0])) << "free motion passes through";
}

TEST_F(PlaceholderFingertipPlaneTest, PadSamplesHaveUnitNormalsAndTheCentreIsDeepest) {
    sut.setTime(0.5 * parameters.press_period_s);
    msgs::ContactSurface surface;
    sut.fillContactSurface(surface);
    ASSERT_THAT(surface.samples.size(), Eq(1U + 8U * static_cast<unsigned>(parameters.pad_rings)));
    double weight_sum = 0.0;
    for (const auto& s : surface.samples) {
        const Eigen::Vector3d n(s.normal_device[0], s.normal_device[1], s.normal_device[2]);
        EXPECT_THAT(n.norm(), DoubleNear(1.0, 1e-12));
        // z_D points from nail to pad; with the distal phalanx flexed by phi in total, the
        // plane's up normal has z_D component -cos(phi).
        EXPECT_THAT(n.z(), DoubleNear(-std::cos(sut.jointAngles().sum()), 1e-12));
        weight_sum += s.weight;
    }
    EXPECT_THAT(weight_sum, DoubleNear(1.0, 1e-12));
    // Signed distances are a plane's: linear in the sample position.
    const auto& centre = surface.samples[0];
    for (const auto& s : surface.samples) {
        const Eigen::Vector3d dp(s.p_device_m[0] - centre.p_device_m[0],
                                 s.p_device_m[1] - centre.p_device_m[1],
                                 s.p_device_m[2] - centre.p_device_m[2]);
        const Eigen::Vector3d n(s.normal_device[0], s.normal_device[1], s.normal_device[2]);
        EXPECT_THAT(s.signed_distance_m - centre.signed_distance_m, DoubleNear(n.dot(dp), 1e-12));
    }
}

}  // namespace
}  // namespace haptic::sim
