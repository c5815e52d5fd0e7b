// The virtual user (hapticemu --user): one hand for the tracker and the devices. Loads the
// shipped config/user.yaml, as hapticemu does.

#include "haptic/config/virtual_user.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "haptic/can/loopback_bus.hpp"
#include "haptic/emu/device_emulator.hpp"
#include "haptic/emu/device_models.hpp"
#include "haptic/emu/virtual_user.hpp"
#include "haptic/softhand/tracking_input.hpp"

namespace haptic::emu {
namespace {

constexpr std::size_t kIndexMcp = 3;  // thumb 0..2, index 3..5 in HandPoseInput::flexion_rad

config::VirtualUserConfig shippedUser() {
    return config::loadVirtualUserConfig(std::string(HAPTIC_CONFIG_DIR) + "/user.yaml");
}

// The user wearing every device of the file on a loopback bus, stepped as hapticemu does.
struct WornDevices {
    explicit WornDevices(const config::VirtualUserConfig& config) : user(config) {
        EmulatorOptions options;
        options.mode = EmulatorMode::kLockstep;  // the models step only when the test says so
        for (const auto& device : config.devices) {
            emulators.push_back(makeEmulator(device, bus, options));
            user.wear(device, *emulators.back());
            if (auto* model = emulators.back()->exoskeletonModel()) {
                exoskeleton = model;
            }
        }
    }
    // One millisecond: the user aims for the intent of t, the exoskeleton's model steps with
    // `force_n` enabled.
    void step(double t_s, double force_n) {
        user.drive(t_s);
        exoskeleton->step(1e-3, force_n, true);
    }

    can::LoopbackBus bus;
    VirtualUser user;
    std::vector<std::unique_ptr<DeviceEmulator>> emulators;
    ExoskeletonModel* exoskeleton{nullptr};
};

TEST(VirtualUser, ShippedFileWearsBothDevicesAndTracksTheDefaultScene) {
    const auto config = shippedUser();
    ASSERT_EQ(config.devices.size(), 2U);
    EXPECT_EQ(config.scene.name, "default");
    EXPECT_EQ(config.tracker.topic, "tracking/hand");
    WornDevices worn(config);
    ASSERT_NE(worn.exoskeleton, nullptr);
    // The intent is the scene's script: the wrist descends onto the block and moves along x.
    const auto start = worn.user.intent(0.0);
    const auto pressed = worn.user.intent(1.0);
    const auto slid = worn.user.intent(3.5);
    EXPECT_LT(pressed.wrist.position_m.z(), start.wrist.position_m.z() - 0.005);
    EXPECT_GT(slid.wrist.position_m.x(), pressed.wrist.position_m.x() + 0.02);
}

// The scene's tracking.loop: the script (6 s) repeats, or holds its last pose.
TEST(VirtualUser, TheScriptLoopsOrHoldsItsLastPoseAsTheSceneSays) {
    auto config = shippedUser();
    ASSERT_TRUE(config.scene.tracking.loop);
    const VirtualUser looping(config);
    config.scene.tracking.loop = false;
    const VirtualUser once(config);
    EXPECT_EQ(looping.intent(7.0).wrist.position_m, looping.intent(1.0).wrist.position_m);
    EXPECT_NE(once.intent(7.0).wrist.position_m, once.intent(1.0).wrist.position_m);
    EXPECT_EQ(once.intent(7.0).wrist.position_m, once.intent(30.0).wrist.position_m);
    EXPECT_EQ(once.intent(1.0).wrist.position_m, looping.intent(1.0).wrist.position_m);
}

TEST(VirtualUser, WithoutForceTheFingerFollowsItsIntent) {
    WornDevices worn(shippedUser());
    double worst_rad = 0.0;
    for (int tick = 0; tick < 6000; ++tick) {  // one period of the script
        const double t = 1e-3 * tick;
        worn.step(t, 0.0);
        const auto intent = worn.user.intent(t);
        const auto actual = worn.user.actualPose(t);
        for (std::size_t j = 0; j < 3; ++j) {
            worst_rad = std::max(worst_rad, std::abs(actual.flexion_rad[kIndexMcp + j] -
                                                     intent.flexion_rad[kIndexMcp + j]));
        }
        // Only the worn finger can differ from the intent, and the wrist never does.
        EXPECT_EQ(actual.wrist.position_m, intent.wrist.position_m);
        EXPECT_EQ(actual.flexion_rad[0], intent.flexion_rad[0]);
        EXPECT_EQ(actual.flexion_rad[6], intent.flexion_rad[6]);
    }
    // The script flexes the finger slowly; the impedance lags it by well under a degree.
    EXPECT_LT(worst_rad, 0.01);
}

TEST(VirtualUser, TheExoskeletonsForceMovesTheFingerAwayFromItsIntent) {
    const auto config = shippedUser();
    WornDevices free_user(config), pushed_user(config), pulled_user(config);
    for (int tick = 0; tick < 1000; ++tick) {
        const double t = 1e-3 * tick;
        free_user.step(t, 0.0);
        pushed_user.step(t, 3.0);   // extends the actuator: flexes the finger
        pulled_user.step(t, -3.0);  // retracts it: extends the finger
    }
    const double free_mcp = free_user.user.actualPose(1.0).flexion_rad[kIndexMcp];
    EXPECT_GT(pushed_user.user.actualPose(1.0).flexion_rad[kIndexMcp], free_mcp + 0.01);
    EXPECT_LT(pulled_user.user.actualPose(1.0).flexion_rad[kIndexMcp], free_mcp - 0.01);
    // The finger settles where the hand impedance balances the force: tau = J^T F.
    std::array<double, 3> jacobian{};
    (void)pushed_user.exoskeleton->linkageStrokeM(pushed_user.exoskeleton->jointRad(), &jacobian);
    const double k_mcp = config.hand_impedance.stiffness_nm_per_rad[0];
    const double deflection = pushed_user.user.actualPose(1.0).flexion_rad[kIndexMcp] -
                              pushed_user.user.intent(1.0).flexion_rad[kIndexMcp];
    EXPECT_NEAR(deflection, jacobian[0] * pushed_user.exoskeleton->forceN() / k_mcp,
                0.2 * std::abs(deflection));
}

// hand_impedance's inertia and damping set how fast the finger gives way to the exoskeleton's
// force (its stiffness, where it settles): four times the damping or ten times the
// inertia, and 20 ms after a 3 N push the finger has moved less; a second later all three
// rest where the same stiffness puts them.
TEST(VirtualUser, TheHandsInertiaAndDampingSetHowFastTheFingerGivesWay) {
    const auto deflection = [](const config::VirtualUserConfig& config, int ticks) {
        WornDevices free_user(config), pushed_user(config);
        for (int tick = 0; tick < ticks; ++tick) {
            const double t = 1e-3 * tick;
            free_user.step(t, 0.0);
            pushed_user.step(t, tick >= 100 ? 3.0 : 0.0);
        }
        const double t = 1e-3 * (ticks - 1);
        return pushed_user.user.actualPose(t).flexion_rad[kIndexMcp] -
               free_user.user.actualPose(t).flexion_rad[kIndexMcp];
    };
    const auto shipped = shippedUser();
    auto damped = shipped;
    auto heavy = shipped;
    for (std::size_t j = 0; j < 3; ++j) {
        damped.hand_impedance.damping_nms_per_rad[j] *= 4.0;
        heavy.hand_impedance.inertia_kg_m2[j] *= 10.0;
    }
    const double early = deflection(shipped, 120);
    ASSERT_GT(early, 0.005);
    EXPECT_LT(deflection(damped, 120), 0.75 * early);
    EXPECT_LT(deflection(heavy, 120), 0.5 * early);
    const double settled = deflection(shipped, 1100);
    EXPECT_NEAR(deflection(damped, 1100), settled, 0.1 * settled);
    EXPECT_NEAR(deflection(heavy, 1100), settled, 0.1 * settled);
}

// How far the user's finger reaches into the virtual block: the script puts the distal
// capsule's lowest point kPressDepth (3 mm) below the top face while pressing; the user's skin
// (the scene's tissue mesh, rigid on its bones) reaches as deep, give or take the mesh's
// departure from the capsule; clear of the block before and after.
TEST(VirtualUser, TheFingerReachesIntoTheBlockAsDeepAsTheScriptPresses) {
    const auto config = shippedUser();
    WornDevices worn(config);
    const auto depth = [&](double t) {
        return worn.user.fingerPenetrationM(config::Finger::kIndex, worn.user.intent(t));
    };
    EXPECT_EQ(depth(0.0), 0.0);
    EXPECT_NEAR(depth(2.0), softhand::PressSlideEdgeScript::kPressDepth, 0.5e-3);
    EXPECT_EQ(depth(5.0), 0.0);  // lifted
    // A finger the model does not simulate (the default scene's is the index alone) has no
    // skin to judge.
    EXPECT_TRUE(
        std::isnan(worn.user.fingerPenetrationM(config::Finger::kThumb, worn.user.intent(2.0))));

    // The exoskeleton's force moves the finger, and with it the depth: extending the actuator
    // flexes the finger further into the block, retracting it lifts the finger out.
    WornDevices pushed(config), pulled(config);
    for (int tick = 0; tick < 2000; ++tick) {
        const double t = 1e-3 * tick;
        pushed.step(t, 3.0);
        pulled.step(t, -3.0);
    }
    const double free_depth = depth(2.0);
    const auto felt_depth = [](WornDevices& user) {
        return user.user.feel(2.0).front().finger_penetration_m;
    };
    EXPECT_GT(felt_depth(pushed), free_depth + 1e-4);
    EXPECT_LT(felt_depth(pulled), free_depth - 1e-4);
}

TEST(VirtualUser, TheTrackerSamplesAtItsRateAndDeliversAfterItsLatency) {
    auto config = shippedUser();
    config.tracker.rate_hz = 90;
    config.tracker.latency_ms = 20.0;
    config.tracker.position_noise_m = 0.0;
    config.tracker.angle_noise_rad = 0.0;
    WornDevices worn(config);
    const std::int64_t origin_ns = 5'000'000'000;
    std::vector<msgs::HandPose> delivered;
    std::vector<std::int64_t> delivered_at_ns;
    for (int tick = 0; tick < 2000; ++tick) {
        const double t = 1e-3 * tick;
        const std::int64_t now_ns = origin_ns + 1'000'000LL * tick;
        worn.step(t, 0.0);
        if (auto pose = worn.user.track(now_ns, t)) {
            delivered.push_back(*pose);
            delivered_at_ns.push_back(now_ns);
        }
    }
    // 2 s at 90 Hz, less the samples still waiting out the 20 ms.
    EXPECT_NEAR(static_cast<double>(delivered.size()), 2.0 * 90.0 - 2.0, 2.0);
    for (std::size_t i = 0; i < delivered.size(); ++i) {
        const auto& pose = delivered[i];
        EXPECT_EQ(pose.header.seq, i + 1);
        EXPECT_EQ(pose.header.source_id.view(), "virtual_user");
        const std::int64_t age_ns = delivered_at_ns[i] - pose.header.stamp_ns;
        EXPECT_GE(age_ns, 20'000'000);
        EXPECT_LT(age_ns, 21'000'000);  // within a tick of the latency
        if (i > 0) {
            const std::int64_t period_ns = pose.header.stamp_ns - delivered[i - 1].header.stamp_ns;
            EXPECT_NEAR(static_cast<double>(period_ns), 1e9 / 90.0, 1e6);
        }
        // Without noise the message is the actual pose at its stamp.
        const double t_sample = 1e-9 * static_cast<double>(pose.header.stamp_ns - origin_ns);
        const auto intent = worn.user.intent(t_sample);
        EXPECT_NEAR(pose.wrist_position_m[2], intent.wrist.position_m.z(), 1e-12);
        ASSERT_EQ(pose.joint_angles_rad.size(), 15U);
    }
}

TEST(VirtualUser, TrackerNoiseHasTheConfiguredSpreadAndIsRepeatablePerSeed) {
    auto config = shippedUser();
    config.tracker.rate_hz = 1000;
    config.tracker.latency_ms = 0.0;
    config.tracker.position_noise_m = 0.001;
    config.tracker.angle_noise_rad = 0.01;
    WornDevices a(config), b(config);
    auto reseeded = config;
    reseeded.tracker.seed = config.tracker.seed + 1;  // tracker.seed in user.yaml
    WornDevices c(reseeded);
    double sum_squared_m = 0.0, sum_squared_rad = 0.0;
    int samples = 0;
    int differing = 0;
    for (int tick = 0; tick < 3000; ++tick) {
        const double t = 1e-3 * tick;
        const std::int64_t now_ns = 1'000'000LL * tick;
        a.step(t, 0.0);
        b.step(t, 0.0);
        c.step(t, 0.0);
        const auto pose_a = a.user.track(now_ns, t);
        const auto pose_b = b.user.track(now_ns, t);
        const auto pose_c = c.user.track(now_ns, t);
        ASSERT_EQ(pose_a.has_value(), pose_b.has_value());
        ASSERT_EQ(pose_a.has_value(), pose_c.has_value());
        if (!pose_a) {
            continue;
        }
        EXPECT_EQ(pose_a->wrist_position_m, pose_b->wrist_position_m) << "same seed, same noise";
        differing += pose_a->wrist_position_m != pose_c->wrist_position_m ? 1 : 0;
        const auto actual = a.user.actualPose(t);
        sum_squared_m += std::pow(pose_a->wrist_position_m[0] - actual.wrist.position_m.x(), 2);
        sum_squared_rad += std::pow(pose_a->joint_angles_rad[0] - actual.flexion_rad[0], 2);
        ++samples;
    }
    ASSERT_GT(samples, 2900);
    EXPECT_EQ(differing, samples) << "another seed, other noise";
    EXPECT_NEAR(std::sqrt(sum_squared_m / samples), 0.001, 0.0001);
    EXPECT_NEAR(std::sqrt(sum_squared_rad / samples), 0.01, 0.001);
}

}  // namespace
}  // namespace haptic::emu
