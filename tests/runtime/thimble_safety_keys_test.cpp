// The thimble's safety keys in hapticd's channel, each changed from the shipped value and its
// effect read off the channel and the emulated device: the pad force limit
// (safety.max_force_n), its rise (safety.max_force_rate_n_per_s), the plate's approach
// speed (safety.max_velocity_m_per_s) and the floor under the sim's pad model
// (safety.min_pad_stiffness_n_per_m). The limiter itself: tactile_test's PadSafety.*.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "haptic/runtime/thimble_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

const runtime::ThimbleChannel& thimbleChannel(RuntimeRig& rig) {
    return static_cast<runtime::ThimbleChannel&>(rig.runtime.channel(kThimble));
}

// The rig's flat object 0.5 mm into the pad, with patches as stiff as the sim's default pad
// (area 1 mm^2 times about 0.2 MPa/mm): the plate matched to it presses a few newtons.
constexpr double kPatchStiffnessNPerM = 200.0;

std::unique_ptr<RuntimeRig> thimbleRig(double max_force_n, double max_force_rate_n_per_s,
                                       double max_velocity_m_per_s) {
    auto rig = std::make_unique<RuntimeRig>([=](std::vector<config::DeviceConfig>& devices) {
        devices[kThimble].safety.max_force_n = max_force_n;
        devices[kThimble].safety.max_force_rate_n_per_s = max_force_rate_n_per_s;
        devices[kThimble].safety.max_velocity_m_per_s = max_velocity_m_per_s;
    });
    for (auto& sample : rig->contact_surface.samples) {
        sample.weight = kPatchStiffnessNPerM;
    }
    return rig;
}

struct PlateRun {
    double peak_force_n{0.0};
    double largest_rise_n{0.0};
    double largest_approach_m{0.0};
    int ticks_to_half_force{-1};
    std::uint8_t flags_seen{0};
};

// Enables rendering on the contact and runs 600 ticks with a 100 Hz sim.
PlateRun renderContact(RuntimeRig& rig) {
    rig.offerContact();
    rig.ticks(20);
    EXPECT_TRUE(rig.command(msgs::CommandKind::kEnable));
    PlateRun run;
    double previous_force = 0.0;
    tactile::PlatformPose previous_pose;
    bool has_previous = false;
    const auto& kinematics_config = rig.devices[kThimble].thimble();
    const tactile::ThimbleKinematics kinematics(kinematics_config);
    for (int i = 0; i < 600; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
        const tactile::PadLimit& limit = thimbleChannel(rig).padLimit();
        run.peak_force_n = std::max(run.peak_force_n, limit.pad_force_n);
        run.largest_rise_n = std::max(run.largest_rise_n, limit.pad_force_n - previous_force);
        previous_force = limit.pad_force_n;
        run.flags_seen |= limit.flags;
        // The plate pose commanded, from the servo targets sent.
        const auto& sent = rig.core.deviceReport(kThimble).thimble.servo_angle_cmd_rad;
        const tactile::ForwardResult fk =
            kinematics.forward({sent[0], sent[1], sent[2]}, kinematics.retractPose());
        if (fk.ok()) {
            if (has_previous) {
                run.largest_approach_m = std::max(
                    run.largest_approach_m,
                    previous_pose.plateNormal().dot(fk.pose.position_m - previous_pose.position_m));
            }
            previous_pose = fk.pose;
            has_previous = true;
        }
    }
    return run;
}

TEST(ThimbleSafetyKeys, MaxForceCapsThePadModelsForce) {
    auto shipped = thimbleRig(1.5, 100.0, 0.1);
    auto tight = thimbleRig(0.3, 100.0, 0.1);
    const PlateRun free_run = renderContact(*thimbleRig(100.0, 1e5, 5.0));
    const PlateRun shipped_run = renderContact(*shipped);
    const PlateRun tight_run = renderContact(*tight);
    // Unlimited, the plate matched to this object presses the pad model harder than both.
    ASSERT_GT(free_run.peak_force_n, 1.5);
    EXPECT_LE(shipped_run.peak_force_n, 1.5 + 1e-9);
    EXPECT_GT(shipped_run.peak_force_n, 1.4) << "held at the limit, not far below it";
    EXPECT_LE(tight_run.peak_force_n, 0.3 + 1e-9);
    EXPECT_GT(tight_run.peak_force_n, 0.25);
    EXPECT_TRUE(tight_run.flags_seen & static_cast<std::uint8_t>(tactile::PadFlag::kForce));
    // The device was told to press less.
    const auto retract = thimbleChannel(*tight).retractServoAngles();
    auto distance = [&retract](RuntimeRig& rig) {
        const auto& sent = rig.core.deviceReport(kThimble).thimble.servo_angle_cmd_rad;
        return std::abs(sent[0] - retract[0]) + std::abs(sent[1] - retract[1]) +
               std::abs(sent[2] - retract[2]);
    };
    EXPECT_LT(distance(*tight), distance(*shipped));
    EXPECT_GT(distance(*tight), 0.0) << "still pressing";
}

// A sim whose weights came out a million times too small (a unit slip: 1e-6 N/m per patch
// here) would leave the force limit nothing to judge: the plate presses as if the pad were
// air. The device file's floor on the pad model's total stiffness keeps the limit acting.
TEST(ThimbleSafetyKeys, MinPadStiffnessKeepsTheForceLimitOnASimWithTinyWeights) {
    const auto withFloor = [](double floor_n_per_m) {
        auto rig = std::make_unique<RuntimeRig>([=](std::vector<config::DeviceConfig>& devices) {
            devices[kThimble].safety.max_force_n = 0.2;
            devices[kThimble].safety.max_force_rate_n_per_s = 1e5;
            devices[kThimble].safety.max_velocity_m_per_s = 5.0;
            devices[kThimble].safety.min_pad_stiffness_n_per_m = floor_n_per_m;
        });
        for (auto& sample : rig->contact_surface.samples) {
            sample.weight = 1e-6;
        }
        return rig;
    };
    auto shipped = withFloor(1000.0);
    auto lowest = withFloor(1.0);  // the schema's least
    const PlateRun shipped_run = renderContact(*shipped);
    const PlateRun lowest_run = renderContact(*lowest);
    // 64 patches at 1 kN/m in total, the object 0.5 mm in: 0.5 N at the object, held at 0.2 N.
    EXPECT_TRUE(shipped_run.flags_seen & static_cast<std::uint8_t>(tactile::PadFlag::kForce));
    EXPECT_LE(shipped_run.peak_force_n, 0.2 + 1e-9);
    EXPECT_GT(shipped_run.peak_force_n, 0.15) << "held at the limit";
    // 1 N/m in total: 0.5 mN at the object, never limited; the plate goes all the way.
    EXPECT_FALSE(lowest_run.flags_seen & static_cast<std::uint8_t>(tactile::PadFlag::kForce));
    EXPECT_LT(lowest_run.peak_force_n, 0.001);
    const auto retract = thimbleChannel(*shipped).retractServoAngles();
    EXPECT_LT(distance(shipped->thimbleTargets(), retract),
              distance(lowest->thimbleTargets(), retract))
        << "the floor held the plate back";
}

TEST(ThimbleSafetyKeys, MaxForceRateLimitsHowFastThePadForceRises) {
    // 100 N/s shipped: 0.1 N per tick; 20 N/s: 0.02 N per tick.
    const PlateRun shipped_run = renderContact(*thimbleRig(100.0, 100.0, 5.0));
    const PlateRun slow_run = renderContact(*thimbleRig(100.0, 20.0, 5.0));
    EXPECT_LE(shipped_run.largest_rise_n, 0.1 + 1e-9);
    EXPECT_LE(slow_run.largest_rise_n, 0.02 + 1e-9);
    EXPECT_GT(slow_run.largest_rise_n, 0.015) << "the rise runs at the limit";
    EXPECT_GT(slow_run.peak_force_n, 1.0) << "and keeps rising: the plate does not stall";
    EXPECT_TRUE(slow_run.flags_seen & static_cast<std::uint8_t>(tactile::PadFlag::kForceRate));
}

TEST(ThimbleSafetyKeys, MaxVelocityLimitsHowFastThePlateApproachesTheFinger) {
    // The servos' own rate limit moves the plate up to about 0.07 m/s; 0.02 m/s is slower.
    const PlateRun fast_run = renderContact(*thimbleRig(100.0, 1e5, 5.0));
    const PlateRun slow_run = renderContact(*thimbleRig(100.0, 1e5, 0.02));
    EXPECT_GT(fast_run.largest_approach_m, 0.03e-3);
    EXPECT_LE(slow_run.largest_approach_m, 0.02e-3 + 1e-9);
    EXPECT_TRUE(slow_run.flags_seen & static_cast<std::uint8_t>(tactile::PadFlag::kApproachSpeed));
}

}  // namespace
}  // namespace haptic::testing
