// hapticemu's models and fault commands.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "device_files.hpp"
#include "haptic/devices/actuator_limits.hpp"
#include "haptic/emu/device_models.hpp"
#include "haptic/emu/fault_injector.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {
namespace {

using testing::exoskeletonDevice;
using testing::thimbleDevice;

TEST(ExoskeletonModel, ActuatorForceIsAFirstOrderLagClampedToTheLimit) {
    const auto device = exoskeletonDevice();
    const auto& actuator = device.exoskeleton().actuator;
    ExoskeletonModel model(device);
    const double dt = 1e-4;
    const int steps = static_cast<int>(std::lround(actuator.lag_time_constant_s / dt));
    for (int i = 0; i < steps; ++i) {
        model.step(dt, 10.0, true);
    }
    // After one time constant: 1 - 1/e of the step, within the discretisation error.
    EXPECT_NEAR(model.forceN(), 10.0 * (1.0 - std::exp(-1.0)), 0.1);
    for (int i = 0; i < 2000; ++i) {
        model.step(1e-3, 1000.0, true);
    }
    // The drive saturates at max_force_n; what reaches the rod, which the force keeps moving,
    // is that on the torque-speed line.
    EXPECT_NEAR(model.forceN(),
                devices::deliverableForceN(actuator.max_force_n, model.rodSpeedMPerS(), actuator),
                1e-6);
    EXPECT_LE(model.forceN(), actuator.max_force_n);
    for (int i = 0; i < 200; ++i) {
        model.step(1e-3, 1000.0, false);
    }
    EXPECT_NEAR(model.forceN(), 0.0, 1e-6);  // disabled: limp
}

// actuator.max_speed_m_per_s is the motor's torque-speed line: pushing the rod along its
// motion the drive delivers less the faster the rod goes, nothing at that speed; braking the
// rod it delivers the full force.
TEST(ExoskeletonModel, TheDriveDeliversLessForceTheFasterItPushesTheRodAlong) {
    const auto device = exoskeletonDevice();
    auto actuator = device.exoskeleton().actuator;
    const double v_max = actuator.max_speed_m_per_s;
    const double f_max = actuator.max_force_n;
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(30.0, 0.0, actuator), 30.0);
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(30.0, 0.5 * v_max, actuator), 0.5 * f_max);
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(-30.0, -0.5 * v_max, actuator), -0.5 * f_max);
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(5.0, 0.5 * v_max, actuator), 5.0)
        << "below the line";
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(30.0, 2.0 * v_max, actuator), 0.0);
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(30.0, -2.0 * v_max, actuator), 30.0) << "braking";
    actuator.max_speed_m_per_s *= 2.0;
    EXPECT_DOUBLE_EQ(devices::deliverableForceN(30.0, 0.5 * v_max, actuator), 0.75 * f_max);
}

// finger.joint_limits_deg bound the emulated finger: as shipped, and with the MCP's range
// narrowed to 10-30 degrees.
class ExoskeletonModelLimits : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(DeviceFile, ExoskeletonModelLimits, ::testing::Values(true, false),
                         [](const auto& info) { return info.param ? "Shipped" : "NarrowMcp"; });

TEST_P(ExoskeletonModelLimits, TheFingerFollowsTheIntentAndYieldsToTheActuator) {
    auto device = exoskeletonDevice();
    if (!GetParam()) {
        std::get<config::ExoskeletonConfig>(device.params).finger.joint_limits_rad[0] = {
            10.0 * std::numbers::pi / 180.0, 30.0 * std::numbers::pi / 180.0};
    }
    ExoskeletonModel free_finger(device), pushed_finger(device);
    double min_q = 10.0, max_q = -10.0;
    for (int i = 0; i < 2000; ++i) {  // one intent period at 0.5 Hz
        free_finger.step(1e-3, 0.0, true);
        pushed_finger.step(1e-3, 20.0, true);
        min_q = std::min(min_q, free_finger.jointRad()[0]);
        max_q = std::max(max_q, free_finger.jointRad()[0]);
    }
    EXPECT_GT(max_q - min_q, GetParam() ? 0.5 : 0.2) << "the user moves the finger";
    // A positive actuator force lengthens the actuator: more stroke than the free finger.
    EXPECT_GT(pushed_finger.strokeM(), free_finger.strokeM());
    const auto& limits = device.exoskeleton().finger.joint_limits_rad;
    for (std::size_t j = 0; j < 3; ++j) {
        EXPECT_GE(pushed_finger.jointRad()[j], limits[j].min);
        EXPECT_LE(pushed_finger.jointRad()[j], limits[j].max);
    }
    EXPECT_GE(min_q, limits[0].min - 1e-12);
    EXPECT_LE(max_q, limits[0].max + 1e-12);
}

// actuator.damping_n_s_per_m is the rod's own damping: released at rest away from the user's
// intent, the finger of a more damped device has moved less 20 ms later.
TEST(ExoskeletonModel, TheRodsOwnDampingSlowsTheFinger) {
    auto damped_device = exoskeletonDevice();
    auto free_device = exoskeletonDevice();
    std::get<config::ExoskeletonConfig>(free_device.params).actuator.damping_n_s_per_m = 0.0;
    std::get<config::ExoskeletonConfig>(damped_device.params).actuator.damping_n_s_per_m = 200.0;
    ExoskeletonModel free_finger(free_device), damped_finger(damped_device);
    const std::array<double, 3> start{-0.3, 0.0, 0.0};  // extended: the rod moves with MCP
    free_finger.placeFinger(start);
    damped_finger.placeFinger(start);
    const double free_start_m = free_finger.strokeM();
    const double damped_start_m = damped_finger.strokeM();
    for (int i = 0; i < 20; ++i) {
        free_finger.step(1e-3, 0.0, false);
        damped_finger.step(1e-3, 0.0, false);
    }
    const double free_travel_m = std::abs(free_finger.strokeM() - free_start_m);
    EXPECT_GT(free_travel_m, 1e-4) << "the user moves the finger";
    EXPECT_LT(std::abs(damped_finger.strokeM() - damped_start_m), 0.5 * free_travel_m);
}

TEST(ExoskeletonModel, LinkageGradientMatchesFiniteDifferences) {
    const auto device = exoskeletonDevice();
    ExoskeletonModel model(device);
    const std::array<double, 3> q{0.4, 0.7, 0.3};
    std::array<double, 3> gradient{};
    const double stroke = model.linkageStrokeM(q, &gradient);
    for (std::size_t j = 0; j < 3; ++j) {
        std::array<double, 3> shifted = q;
        shifted[j] += 1e-6;
        EXPECT_NEAR((model.linkageStrokeM(shifted, nullptr) - stroke) / 1e-6, gradient[j], 1e-6);
    }
}

TEST(ThimbleModel, ServosAreRateLimitedAndClampedToTheirRange) {
    const auto device = thimbleDevice();
    const auto& servos = device.thimble().servos;
    ThimbleModel model(device);
    const std::array<double, 3> start = model.angleRad();
    model.step(1e-3, {-10.0, -10.0, start[2]});
    EXPECT_NEAR(model.angleRad()[0], start[0] - servos.max_rate_rad_per_s * 1e-3, 1e-12);
    EXPECT_NEAR(model.angleRad()[1], start[1] - servos.max_rate_rad_per_s * 1e-3, 1e-12);
    for (int i = 0; i < 5000; ++i) {
        model.step(1e-3, {10.0, -10.0, std::nan("")});
    }
    EXPECT_NEAR(model.angleRad()[0], servos.max_rad, 1e-9);
    EXPECT_NEAR(model.angleRad()[1], servos.min_rad, 1e-9);
    EXPECT_EQ(model.angleRad()[2], start[2]);  // NaN target: hold
}

// Powered on, the plate stands at the retract pose, off the finger: the pose hapticd sends
// first, so a user who put the thimble on first is never pressed before hapticd comes up.
TEST(ThimbleModel, PowersOnAtTheRetractPose) {
    const auto device = thimbleDevice();
    const ThimbleModel model(device);
    const tactile::ThimbleKinematics kinematics(device.thimble());
    const tactile::ForwardResult pose = kinematics.forward(model.angleRad());
    ASSERT_TRUE(pose.ok());
    EXPECT_NEAR(pose.dofs.height_m, kinematics.retractPose().height_m, 1e-9);
    EXPECT_NEAR(pose.dofs.tilt_x_rad, 0.0, 1e-9);
    EXPECT_NEAR(pose.dofs.tilt_y_rad, 0.0, 1e-9);
    EXPECT_GT(pose.dofs.height_m, device.thimble().finger_calibration.contact_height_m + 0.005);
}

TEST(FaultInjector, ParsesCommandsAndExplainsBadOnes) {
    FaultInjector faults;
    std::string error;
    EXPECT_TRUE(faults.command("heartbeat stop", error));
    EXPECT_TRUE(faults.heartbeatStopped());
    EXPECT_TRUE(faults.command("  fault 2 \n", error));
    EXPECT_EQ(faults.deviceFault(), 2);
    EXPECT_TRUE(faults.takeFaultChange());
    EXPECT_FALSE(faults.takeFaultChange());
    EXPECT_TRUE(faults.command("busoff", error));
    EXPECT_TRUE(faults.busOff());
    EXPECT_TRUE(faults.command("state stop", error));
    EXPECT_TRUE(faults.stateStopped());
    EXPECT_TRUE(faults.command("state start", error));
    EXPECT_FALSE(faults.stateStopped());
    EXPECT_TRUE(faults.command("state stop", error));
    EXPECT_TRUE(faults.command("clear", error));
    EXPECT_FALSE(faults.heartbeatStopped());
    EXPECT_FALSE(faults.stateStopped());
    EXPECT_FALSE(faults.busOff());
    EXPECT_EQ(faults.deviceFault(), 0);
    EXPECT_FALSE(faults.command("drop many", error));
    EXPECT_THAT(error, ::testing::HasSubstr("unknown fault command 'drop many'"));
    EXPECT_FALSE(faults.command("fault 7", error));
}

}  // namespace
}  // namespace haptic::emu
