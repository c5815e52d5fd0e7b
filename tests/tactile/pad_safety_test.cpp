// The thimble's safety limits on the plate (haptic/tactile/pad_safety.hpp): the pad model's
// force, its rise per tick and the plate's approach speed, each on a flat pad whose forces
// are known in closed form.

#include "haptic/tactile/pad_safety.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "allocation_counter.hpp"

namespace haptic::tactile {
namespace {

constexpr double kPadZ = 0.018;         // the undeformed pad, device frame
constexpr double kRetractZ = 0.024;     // the plate far from it
constexpr double kWeight = 50.0;        // N/m per patch
constexpr double kPlateRadius = 0.008;  // the shipped plate
constexpr double kRimBlend = 0.001;

// A plate at height z, untilted: its normal (into the finger) is -z, so it presses the pad
// once z < kPadZ.
PlatformPose plateAt(double z) {
    PlatformPose pose;
    pose.position_m = Eigen::Vector3d(0.0, 0.0, z);
    return pose;
}

// Nine patches 1 mm apart around the plate's centre.
msgs::ContactSurface flatPad() {
    msgs::ContactSurface surface;
    for (int i = -1; i <= 1; ++i) {
        for (int j = -1; j <= 1; ++j) {
            msgs::ContactSample sample;
            sample.p_device_m = {0.001 * i, 0.001 * j, kPadZ};
            sample.signed_distance_m = -0.001;
            sample.normal_device = {0.0, 0.0, 1.0};
            sample.weight = kWeight;
            surface.samples.push_back(sample);
        }
    }
    return surface;
}

PadSafetySettings loose() {
    PadSafetySettings settings;
    settings.max_force_n = 100.0;
    settings.max_force_rate_n_per_s = 1e9;
    settings.max_approach_speed_m_per_s = 1e3;
    settings.period_s = 1e-3;
    settings.plate_radius_m = kPlateRadius;
    settings.rim_blend_m = kRimBlend;
    return settings;
}

// The blend the channel walks: the retract pose at gain 0, `target_z` at gain 1.
auto blendTo(double target_z) {
    return [target_z](double gain, PlatformPose& pose) {
        pose = plateAt(kRetractZ + gain * (target_z - kRetractZ));
        return true;
    };
}

// One tick as the channel runs it when the servos follow exactly: limit, then send that pose.
template <class PoseAt>
PadLimit tick(PadSafetyLimiter& limiter, double gain, const msgs::ContactSurface* surface,
              PoseAt&& pose_at) {
    const PadLimit limit = limiter.limit(gain, surface, pose_at);
    EXPECT_TRUE(limit.has_pose);
    (void)limiter.commanded(limit.pose, surface);
    return limit;
}

TEST(PadSafety, ThePadModelPressesBackWithTheStiffnessOfEveryPatchThePlatePasses) {
    const msgs::ContactSurface pad = flatPad();
    EXPECT_EQ(padForceN(plateAt(kPadZ + 0.0005), pad, kPlateRadius, kRimBlend), 0.0);
    EXPECT_NEAR(padForceN(plateAt(kPadZ - 0.001), pad, kPlateRadius, kRimBlend),
                9 * kWeight * 0.001, 1e-12);
    EXPECT_NEAR(padForceN(plateAt(kPadZ - 0.002), pad, kPlateRadius, kRimBlend),
                9 * kWeight * 0.002, 1e-12);

    // Beyond the rim a patch is not pressed; in the rim's blend it counts by the smoothstep.
    msgs::ContactSurface rim = pad;
    rim.samples.clear();
    msgs::ContactSample outside = pad.samples[0];
    outside.p_device_m = {0.009, 0.0, kPadZ};
    rim.samples.push_back(outside);
    EXPECT_EQ(padForceN(plateAt(kPadZ - 0.001), rim, kPlateRadius, kRimBlend), 0.0);
    rim.samples[0].p_device_m = {0.0075, 0.0, kPadZ};  // halfway through the blend
    EXPECT_NEAR(padForceN(plateAt(kPadZ - 0.001), rim, kPlateRadius, kRimBlend),
                0.5 * kWeight * 0.001, 1e-12);

    // Patches with no stiffness or a NaN add nothing.
    msgs::ContactSurface bad = pad;
    bad.samples[0].weight = std::nan("");
    bad.samples[1].p_device_m[2] = std::nan("");
    EXPECT_NEAR(padForceN(plateAt(kPadZ - 0.001), bad, kPlateRadius, kRimBlend),
                7 * kWeight * 0.001, 1e-12);
}

// The floor under the pad model's total stiffness: a softer surface is judged as if each
// patch were stiffened by one factor, a surface of no stiffness as if the floor were shared
// evenly; a stiffer one as it is.
TEST(PadSafety, APadSofterThanTheFloorIsJudgedAtTheFloor) {
    msgs::ContactSurface soft = flatPad();  // nine patches of 50 N/m: 450 N/m in total
    const PlatformPose pressed = plateAt(kPadZ - 0.001);
    EXPECT_NEAR(padForceN(pressed, soft, kPlateRadius, kRimBlend, 300.0), 0.45, 1e-12);
    EXPECT_NEAR(padForceN(pressed, soft, kPlateRadius, kRimBlend, 900.0), 0.9, 1e-12);
    soft.samples[0].weight = 0.0;  // 400 N/m, the missing patch stays out
    EXPECT_NEAR(padForceN(pressed, soft, kPlateRadius, kRimBlend, 800.0), 0.8, 1e-12);
    for (auto& sample : soft.samples) {
        sample.weight = 0.0;
    }
    EXPECT_EQ(padForceN(pressed, soft, kPlateRadius, kRimBlend), 0.0);
    EXPECT_NEAR(padForceN(pressed, soft, kPlateRadius, kRimBlend, 900.0), 0.9, 1e-12);
}

TEST(PadSafety, WithinTheLimitsThePlateGoesWhereItIsAsked) {
    PadSafetyLimiter limiter(loose());
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    const msgs::ContactSurface pad = flatPad();
    const PadLimit limit = tick(limiter, 0.9, &pad, blendTo(kPadZ - 0.002));
    EXPECT_EQ(limit.gain, 0.9);
    EXPECT_EQ(limit.flags, 0);
    const double z = kRetractZ + 0.9 * (kPadZ - 0.002 - kRetractZ);  // 1.2 mm in
    EXPECT_NEAR(limit.pad_force_n, 9 * kWeight * (kPadZ - z), 1e-12);
}

TEST(PadSafety, MaxForceHoldsThePlateWhereThePadModelReachesIt) {
    PadSafetySettings settings = loose();
    settings.max_force_n = 9 * kWeight * 0.001;  // reached 1 mm into the pad
    PadSafetyLimiter limiter(settings);
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    const msgs::ContactSurface pad = flatPad();
    const PadLimit limit = tick(limiter, 1.0, &pad, blendTo(kPadZ - 0.002));
    EXPECT_EQ(limit.flags, static_cast<std::uint8_t>(PadFlag::kForce));
    EXPECT_LE(limit.pad_force_n, settings.max_force_n);
    // The gain where the plate is 1 mm in, within the bisection's 1/65536.
    const double expected_gain = (kRetractZ - (kPadZ - 0.001)) / (kRetractZ - (kPadZ - 0.002));
    EXPECT_LE(limit.gain, expected_gain);
    EXPECT_GT(limit.gain, expected_gain - 1.0 / 65536.0);

    // A smaller limit keeps the plate farther back: the key decides.
    settings.max_force_n *= 0.5;
    PadSafetyLimiter softer(settings);
    (void)softer.commanded(plateAt(kRetractZ), nullptr);
    const PadLimit half = tick(softer, 1.0, &pad, blendTo(kPadZ - 0.002));
    EXPECT_LE(half.pad_force_n, settings.max_force_n);
    EXPECT_LT(half.gain, limit.gain);
}

TEST(PadSafety, ThePadForceRisesAtMostAtMaxForceRateAndFallsAtOnce) {
    PadSafetySettings settings = loose();
    settings.max_force_rate_n_per_s = 100.0;  // 0.1 N per 1 ms tick
    PadSafetyLimiter limiter(settings);
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    const msgs::ContactSurface pad = flatPad();
    const double target_force = 9 * kWeight * 0.002;  // 0.9 N
    double previous = 0.0;
    int ticks = 0;
    for (; ticks < 100 && previous < target_force - 1e-9; ++ticks) {
        const PadLimit limit = tick(limiter, 1.0, &pad, blendTo(kPadZ - 0.002));
        ASSERT_LE(limit.pad_force_n, previous + 0.1 + 1e-12) << "tick " << ticks;
        previous = limit.pad_force_n;
    }
    // 0.9 N at 0.1 N per tick: 9 ticks, one more for the bisection's resolution.
    EXPECT_GE(ticks, 9);
    EXPECT_LE(ticks, 11);
    // Releasing is never slowed.
    const PadLimit release = tick(limiter, 0.0, &pad, blendTo(kPadZ - 0.002));
    EXPECT_EQ(release.pad_force_n, 0.0);
    EXPECT_EQ(release.flags, 0);

    // A finger pushing into a plate that stays put raises the force too (4.5 kN/m at 0.1 mm
    // per tick: 0.45 N per tick): the plate gives way.
    PadSafetyLimiter held(settings);
    (void)held.commanded(plateAt(kRetractZ), nullptr);
    msgs::ContactSurface moving = pad;
    for (auto& sample : moving.samples) {
        sample.weight = 500.0;
    }
    double force = 0.0;
    int gave_way = 0;
    for (int i = 0; i < 20; ++i) {
        for (auto& sample : moving.samples) {
            sample.p_device_m[2] = kPadZ + 0.0001 * i;  // 0.1 mm per tick towards the plate
        }
        const PadLimit limit = tick(held, 1.0, &moving, blendTo(kPadZ));
        ASSERT_LE(limit.pad_force_n, force + 0.1 + 1e-12) << "tick " << i;
        if (limit.gain < 1.0) {
            ++gave_way;
            EXPECT_TRUE(limit.flags & static_cast<std::uint8_t>(PadFlag::kForceRate));
        }
        force = limit.pad_force_n;
    }
    EXPECT_GT(gave_way, 5);
}

// On a stiff pad a search over the whole stroke stalls the plate short of the pad: its 16
// steps resolve 8 mm / 65536 = 0.12 um, 55 mN on this 450 kN/m pad, and no step fits a 0.02 N
// rise. The search resumes from last tick's gain and resolves 1/65536 of the quarter of the
// stroke that is left, 14 mN, so the force creeps up.
TEST(PadSafety, OnAStiffPadTheForceStillRisesAtTheRateLimit) {
    PadSafetySettings settings = loose();
    settings.max_force_rate_n_per_s = 20.0;  // 0.02 N per tick
    PadSafetyLimiter limiter(settings);
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    msgs::ContactSurface stiff = flatPad();
    for (auto& sample : stiff.samples) {
        sample.weight = 50000.0;  // 450 kN/m in all
    }
    double previous = 0.0;
    for (int i = 0; i < 100; ++i) {
        const PadLimit limit = tick(limiter, 1.0, &stiff, blendTo(kPadZ - 0.002));
        ASSERT_LE(limit.pad_force_n, previous + 0.02 + 1e-12) << "tick " << i;
        previous = limit.pad_force_n;
    }
    EXPECT_GT(previous, 0.5) << "100 ticks at up to 0.02 N each";
}

// A tilt about the plate's centre: the centre stays, the rim swings towards the finger.
TEST(PadSafety, TheApproachLimitHoldsAtTheRimToo) {
    PadSafetySettings settings = loose();
    settings.max_approach_speed_m_per_s = 0.1;  // 0.1 mm per tick
    PadSafetyLimiter limiter(settings);
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    const double full_tilt_rad = std::asin(0.001 / kPlateRadius);  // rim 1 mm towards the finger
    const auto tilt = [&](double gain, PlatformPose& pose) {
        pose = plateAt(kRetractZ);
        pose.rotation = Eigen::AngleAxisd(gain * full_tilt_rad, Eigen::Vector3d::UnitX()).matrix();
        return true;
    };
    const PadLimit limit = tick(limiter, 1.0, nullptr, tilt);
    EXPECT_TRUE(limit.flags & static_cast<std::uint8_t>(PadFlag::kApproachSpeed));
    EXPECT_GT(limit.gain, 0.08);
    EXPECT_LT(limit.gain, 0.11);  // 0.1 mm of the rim's 1 mm
}

TEST(PadSafety, ThePlateApproachesAtMostAtMaxVelocityAndWithdrawsAtOnce) {
    PadSafetySettings settings = loose();
    settings.max_approach_speed_m_per_s = 0.1;  // 0.1 mm per 1 ms tick
    PadSafetyLimiter limiter(settings);
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    // No pad known: only the speed limit applies.
    double z = kRetractZ;
    const double target_z = kRetractZ - 0.004;
    int ticks = 0;
    for (; ticks < 100; ++ticks) {
        PlatformPose pose;
        const PadLimit limit = tick(limiter, 1.0, nullptr, blendTo(target_z));
        blendTo(target_z)(limit.gain, pose);
        ASSERT_LE(z - pose.position_m.z(), 1e-4 + 1e-12) << "tick " << ticks;
        z = pose.position_m.z();
        if (limit.gain == 1.0) {
            break;
        }
        EXPECT_EQ(limit.flags, static_cast<std::uint8_t>(PadFlag::kApproachSpeed));
    }
    // 4 mm at 0.1 mm per tick: 40 ticks, a few more for the bisection's resolution.
    EXPECT_GE(ticks, 39);
    EXPECT_LE(ticks, 45);
    const PadLimit withdraw = tick(limiter, 0.0, nullptr, blendTo(target_z));
    EXPECT_EQ(withdraw.gain, 0.0);
    EXPECT_EQ(withdraw.flags, 0);
}

// Servo angles to a plate height, for judgeStep: every radian of the mean angle brings the
// plate 5 mm nearer the pad; past `known_up_to_rad` there is no pose (the servos' own rate
// limits can leave the angles off the platform's assembly).
auto servoForward(double known_up_to_rad) {
    return [known_up_to_rad](const ServoAngles& angles, ForwardResult& result) {
        const double mean = (angles[0] + angles[1] + angles[2]) / 3.0;
        result = ForwardResult{};
        if (mean > known_up_to_rad) {
            result.error = KinematicsError::kParasiticNotConverged;
            return;
        }
        result.pose = plateAt(kRetractZ - 0.005 * mean);
    };
}

TEST(PadSafety, AServoStepThatKeepsTheLimitsIsSentWhole) {
    const PadSafetyLimiter limiter(loose());
    const msgs::ContactSurface pad = flatPad();
    const auto sent =
        limiter.judgeStep({0.0, 0.0, 0.0}, {0.5, 0.4, 0.6}, &pad, false, servoForward(10.0));
    EXPECT_FALSE(sent.shortened);
    EXPECT_EQ(sent.servo_rad, (ServoAngles{0.5, 0.4, 0.6}));
    ASSERT_TRUE(sent.forward.ok());
    EXPECT_NEAR(sent.forward.pose.position_m.z(), kRetractZ - 0.0025, 1e-15);
}

// A step whose pose is unknown cannot be judged: only the part of it that can, and keeps the
// limits, is sent; where none can, the servos hold. It never goes out unjudged.
TEST(PadSafety, AServoStepWithNoPoseIsCutBackToWhatCanBeJudgedOrHeld) {
    const PadSafetyLimiter limiter(loose());
    const msgs::ContactSurface pad = flatPad();
    const ServoAngles previous{0.1, 0.1, 0.1};
    const auto cut = limiter.judgeStep(previous, {1.0, 1.0, 1.0}, &pad, false, servoForward(0.3));
    EXPECT_TRUE(cut.shortened);
    ASSERT_TRUE(cut.forward.ok());
    for (double angle : cut.servo_rad) {
        EXPECT_LE(angle, 0.3);
        EXPECT_GT(angle, 0.3 - 1e-4) << "the whole known part is sent";
    }
    // Known only up to a hair past the angles held: no bisection step of the 0.9 rad is.
    const auto held =
        limiter.judgeStep(previous, {1.0, 1.0, 1.0}, &pad, false, servoForward(0.1 + 1e-9));
    EXPECT_TRUE(held.shortened);
    EXPECT_EQ(held.servo_rad, previous);
    ASSERT_TRUE(held.forward.ok());
    EXPECT_NEAR(held.forward.pose.position_m.z(), kRetractZ - 0.0005, 1e-15);
    // Not even the angles held have a pose now: held all the same, reported unknown.
    const auto unknown =
        limiter.judgeStep(previous, {1.0, 1.0, 1.0}, &pad, false, servoForward(0.0));
    EXPECT_EQ(unknown.servo_rad, previous);
    EXPECT_FALSE(unknown.forward.ok());
}

// The finger pushed into the plate: the pose held last tick already breaks the force limit and
// no part of the (withdrawing) step keeps it. The step goes on whole, towards the pose limit()
// chose; holding would keep the plate pressing harder. One that presses harder by more than
// the rate limit allows in a tick is held, unless it heads for the retract pose, which nothing
// holds up.
TEST(PadSafety, AKnownStepThatNoFractionCanMendGoesOnWholeUnlessItPressesHarder) {
    PadSafetySettings settings = loose();
    settings.max_force_n = 0.2;
    settings.max_force_rate_n_per_s = 100.0;  // 0.1 N per tick
    const PadSafetyLimiter limiter(settings);
    const msgs::ContactSurface pad = flatPad();
    // Angles to heights: 3 mm and 2 mm into the pad (1.35 N and 0.9 N on nine 50 N/m patches).
    const double deep = (kRetractZ - (kPadZ - 0.003)) / 0.005;
    const double less_deep = (kRetractZ - (kPadZ - 0.002)) / 0.005;
    const auto sent = limiter.judgeStep({deep, deep, deep}, {less_deep, less_deep, less_deep}, &pad,
                                        false, servoForward(10.0));
    EXPECT_FALSE(sent.shortened);
    EXPECT_EQ(sent.servo_rad, (ServoAngles{less_deep, less_deep, less_deep}));
    EXPECT_TRUE(sent.forward.ok());
    // A step from there that would press harder still is held.
    const double deeper = (kRetractZ - (kPadZ - 0.004)) / 0.005;
    const auto held = limiter.judgeStep({deep, deep, deep}, {deeper, deeper, deeper}, &pad, false,
                                        servoForward(10.0));
    EXPECT_TRUE(held.shortened);
    EXPECT_EQ(held.servo_rad, (ServoAngles{deep, deep, deep}));
    EXPECT_TRUE(held.forward.ok());
    // 0.1 mm deeper: 0.045 N more, within the 0.1 N a tick may add. It goes on.
    const double a_little_deeper = (kRetractZ - (kPadZ - 0.0031)) / 0.005;
    const ServoAngles little{a_little_deeper, a_little_deeper, a_little_deeper};
    const auto crept =
        limiter.judgeStep({deep, deep, deep}, little, &pad, false, servoForward(10.0));
    EXPECT_FALSE(crept.shortened);
    EXPECT_EQ(crept.servo_rad, little);
    // Heading for the retract pose: sent as it is, however it presses or whether its pose is
    // known.
    const ServoAngles deeper_step{deeper, deeper, deeper};
    EXPECT_EQ(limiter.judgeStep({deep, deep, deep}, deeper_step, &pad, true, servoForward(10.0))
                  .servo_rad,
              deeper_step);
    EXPECT_EQ(
        limiter.judgeStep({deep, deep, deep}, deeper_step, &pad, true, servoForward(0.0)).servo_rad,
        deeper_step);
}

TEST(PadSafety, LimitingAllocatesNothing) {
    PadSafetySettings settings = loose();
    settings.max_force_n = 0.2;
    settings.max_force_rate_n_per_s = 100.0;
    settings.max_approach_speed_m_per_s = 0.1;
    PadSafetyLimiter limiter(settings);
    (void)limiter.commanded(plateAt(kRetractZ), nullptr);
    const msgs::ContactSurface pad = flatPad();
    double sum = 0.0;
    testing::ScopedAllocationCounter counter;
    for (int i = 0; i < 1000; ++i) {
        sum += tick(limiter, (i % 100) / 99.0, &pad, blendTo(kPadZ - 0.002)).gain;
        sum += limiter.judgeStep({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, &pad, false, servoForward(0.5))
                   .servo_rad[0];
    }
    EXPECT_EQ(counter.allocations(), 0U);
    EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace haptic::tactile
