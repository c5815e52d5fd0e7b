// The virtual user's pad under the thimble (UserPad): the plate where the measured servo angles
// put it, pressing the distal phalanx (a sphere at half-length 0, the scene's phalanx
// otherwise). The plate poses come from the thimble's inverse kinematics and the expected
// indentations from sampling the pad's surface, so the test shares no formula with the pad's
// own geometry.

#include "haptic/emu/user_pad.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "haptic/config/device.hpp"
#include "haptic/config/virtual_user.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {
namespace {

config::ThimbleConfig shippedThimble() {
    return config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/thimble.yaml")
        .thimble();
}

config::UserPadConfig shippedPad() {
    return config::loadVirtualUserConfig(std::string(HAPTIC_CONFIG_DIR) + "/user.yaml").pad;
}

// The deepest any point of the sphere lies beyond the plate's plane (the side the plate came
// from), by sampling its surface on a fine grid: the indentation, found the slow way. Plain
// doubles in the loop: the sanitizer build is unoptimised, where a million Eigen temporaries
// per case take minutes.
double deepestSphereSample(const Eigen::Vector3d& centre, double radius,
                           const tactile::PlatformPose& plate) {
    const Eigen::Vector3d normal = plate.plateNormal();  // from the plate into the finger
    // (plate - point) . normal = (plate - centre) . normal - radius * (direction . normal)
    const double centre_depth = (plate.position_m - centre).dot(normal);
    const double nx = normal.x(), ny = normal.y(), nz = normal.z();
    double deepest = -std::numeric_limits<double>::infinity();
    constexpr int kSteps = 720;
    for (int i = 0; i <= kSteps; ++i) {
        const double polar = std::numbers::pi * i / kSteps;
        const double sin_polar = std::sin(polar);
        const double cos_polar = std::cos(polar);
        for (int j = 0; j < 2 * kSteps; ++j) {
            const double azimuth = std::numbers::pi * j / kSteps;
            const double along_normal = sin_polar * std::cos(azimuth) * nx +
                                        sin_polar * std::sin(azimuth) * ny + cos_polar * nz;
            deepest = std::max(deepest, centre_depth - radius * along_normal);
        }
    }
    return deepest;
}

tactile::InverseResult plateAt(const config::ThimbleConfig& thimble, double height_m,
                               double tilt_x_rad, double tilt_y_rad) {
    const tactile::ThimbleKinematics kinematics(thimble);
    return kinematics.inverse({height_m, tilt_x_rad, tilt_y_rad}, false);
}

// The deepest point of the phalanx's surface (a cylinder of `radius` about `axis` over
// [-half, half] from `centre`, flat at -half, and the round tip at +half) that lies over the
// plate's disc, past the plate's plane, by sampling the surface: the indentation, the slow way.
// Plain doubles in the loop, as above (three million samples per case).
double deepestPhalanxSample(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis, double half,
                            double radius, const tactile::PlatformPose& plate,
                            double plate_radius) {
    const Eigen::Vector3d normal = plate.plateNormal();
    const Eigen::Vector3d side_u = axis.unitOrthogonal();
    const Eigen::Vector3d side_v = axis.cross(side_u);
    const double n[3] = {normal.x(), normal.y(), normal.z()};
    const Eigen::Vector3d from_plate = centre - plate.position_m;
    const double c[3] = {from_plate.x(), from_plate.y(), from_plate.z()};
    const double plate_radius_sq = plate_radius * plate_radius;
    double deepest = -std::numeric_limits<double>::infinity();
    // offset = centre + along * axis + across (from the plate's centre)
    const auto sample = [&](const double along_axis[3], const double across[3]) {
        double offset[3];
        for (int k = 0; k < 3; ++k) {
            offset[k] = c[k] + along_axis[k] + across[k];
        }
        const double height = offset[0] * n[0] + offset[1] * n[1] + offset[2] * n[2];
        double in_plane_sq = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double in_plane = offset[k] - height * n[k];
            in_plane_sq += in_plane * in_plane;
        }
        if (in_plane_sq <= plate_radius_sq) {
            deepest = std::max(deepest, -height);
        }
    };
    constexpr int kAround = 720;
    constexpr int kAlong = 4000;
    for (int i = 0; i < kAround; ++i) {
        const double angle = 2.0 * std::numbers::pi * i / kAround;
        const Eigen::Vector3d radial = std::cos(angle) * side_u + std::sin(angle) * side_v;
        const double across[3] = {radius * radial.x(), radius * radial.y(), radius * radial.z()};
        for (int j = 0; j <= kAlong; ++j) {
            const double along = -half + 2.0 * half * j / kAlong;
            const double along_axis[3] = {along * axis.x(), along * axis.y(), along * axis.z()};
            sample(along_axis, across);
        }
        for (int j = 0; j <= kAround / 4; ++j) {  // the tip's hemisphere
            const double polar = 0.5 * std::numbers::pi * j / (kAround / 4);
            const double tip = half + radius * std::cos(polar);
            const double along_axis[3] = {tip * axis.x(), tip * axis.y(), tip * axis.z()};
            const double tip_across[3] = {std::sin(polar) * across[0], std::sin(polar) * across[1],
                                          std::sin(polar) * across[2]};
            sample(along_axis, tip_across);
        }
    }
    return deepest;
}

TEST(UserPad, ALevelPlateIndentsThePadByItsHeightPastFirstContact) {
    const auto thimble = shippedThimble();
    // The shipped pad, and user.yaml's pad.radius_m and pad.effective_modulus_pa changed.
    auto other = shippedPad();
    other.radius_m = 0.010;
    other.effective_modulus_pa = 2.0 * other.effective_modulus_pa;
    for (const auto& pad : {shippedPad(), other}) {
        UserPad user_pad(thimble, pad, 0.0);
        // The pad's outermost point: the phalanx's centre 12 mm from the device origin
        // (T_finger_device) plus the fingertip's radius.
        const double first_contact = user_pad.firstContactHeightM();
        EXPECT_NEAR(first_contact, 0.012 + pad.radius_m, 1e-12);
        for (const double depth : {0.0005, 0.001, 0.002, 0.0035}) {
            const auto plate = plateAt(thimble, first_contact - depth, 0.0, 0.0);
            ASSERT_TRUE(plate.ok());
            const FeltPadContact felt = user_pad.feel(plate.servo_rad);
            ASSERT_TRUE(felt.pose_known);
            EXPECT_NEAR(felt.indentation_m, depth, 1e-9);
            // Hertz: F = 4/3 E* sqrt(R) delta^1.5, straight into the finger (-z), on the axis.
            const double hertz = 4.0 / 3.0 * pad.effective_modulus_pa * std::sqrt(pad.radius_m) *
                                 std::pow(depth, 1.5);
            EXPECT_NEAR(felt.force_device_n.z(), -hertz, 1e-9);
            EXPECT_NEAR(felt.force_device_n.head<2>().norm(), 0.0, 1e-9);
            EXPECT_NEAR(felt.moment_device_nm.norm(), 0.0, 1e-9);
        }
    }
    // The shipped pad: about 0.24 N at 1 mm, 0.67 N at 2 mm (E* 62.7 kPa, R 8 mm); the other,
    // twice as stiff and 10 mm round: 0.24 x 2 x sqrt(10 / 8).
    EXPECT_NEAR(UserPad(thimble, shippedPad(), 0.0).forceAt(0.001), 0.236, 0.002);
    EXPECT_NEAR(UserPad(thimble, shippedPad(), 0.0).forceAt(0.002), 0.669, 0.002);
    EXPECT_NEAR(UserPad(thimble, other, 0.0).forceAt(0.001), 0.236 * 2.0 * std::sqrt(1.25), 0.005);
}

TEST(UserPad, ATiltedPlateIndentsAsDeepAsTheSphereReachesPastIt) {
    const auto thimble = shippedThimble();
    const auto pad = shippedPad();
    UserPad user_pad(thimble, pad, 0.0);
    const double first_contact = user_pad.firstContactHeightM();
    const Eigen::Vector3d centre(0.0, 0.0, 0.012);  // -T_finger_device's translation
    int pressed = 0;
    for (const double tilt_deg : {-20.0, -8.0, 5.0, 15.0}) {
        for (const double depth : {0.0005, 0.002}) {
            const double tilt = tilt_deg * std::numbers::pi / 180.0;
            const auto plate = plateAt(thimble, first_contact - depth, tilt, 0.4 * tilt);
            ASSERT_TRUE(plate.ok()) << tilt_deg;
            const FeltPadContact felt = user_pad.feel(plate.servo_rad);
            ASSERT_TRUE(felt.pose_known);
            const double expected =
                std::max(0.0, deepestSphereSample(centre, pad.radius_m, plate.pose));
            // The grid's spacing (pi / 720 rad) bounds its error by R (1 - cos) < 1e-7 m.
            EXPECT_NEAR(felt.indentation_m, expected, 2e-7) << tilt_deg << " " << depth;
            EXPECT_NEAR(felt.force_device_n.norm(), user_pad.forceAt(felt.indentation_m), 1e-12);
            if (felt.indentation_m > 0.0) {
                ++pressed;
                // Along the plate's normal, and about the origin from the pressed point.
                EXPECT_NEAR(felt.force_device_n.normalized().dot(plate.pose.plateNormal()), 1.0,
                            1e-12);
                EXPECT_TRUE(felt.moment_device_nm.isApprox(
                    felt.point_device_m.cross(felt.force_device_n), 1e-12));
                // The pressed point is on the plate and on the sphere's axis along the normal.
                EXPECT_NEAR(
                    (felt.point_device_m - plate.pose.position_m).dot(plate.pose.plateNormal()),
                    0.0, 1e-12);
            }
        }
    }
    EXPECT_GE(pressed, 6);
}

// A thimble mounted off the phalanx's axis and turned on it: the pad's centre is where
// T_finger_device puts the finger's origin in the device frame, found here by inverting the
// mount point by point (p_finger = R p_device + t, solved for the p_device that maps to 0).
TEST(UserPad, AnOffAxisTurnedMountMovesThePadWhereTheTransformPutsIt) {
    auto thimble = shippedThimble();
    auto& mount = thimble.finger_calibration.T_finger_device;
    mount.translation_m = {0.0015, -0.001, -0.0125};
    mount.rpy_rad = {0.05, -0.04, 0.6};
    const auto pad = shippedPad();
    UserPad user_pad(thimble, pad, 0.0);
    const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()) *
                                      Eigen::AngleAxisd(-0.04, Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()))
                                         .toRotationMatrix();
    const Eigen::Vector3d t(0.0015, -0.001, -0.0125);
    // The finger's origin maps from the device point c: R c + t = 0.
    const Eigen::Vector3d& c = user_pad.centreDeviceM();
    EXPECT_NEAR((rotation * c + t).norm(), 0.0, 1e-15);
    // A transposed rotation would put it elsewhere: the test can tell the two apart.
    EXPECT_GT((rotation.transpose() * c + t).norm(), 1e-4);

    // And the plate presses that sphere: indentation against the sampled surface.
    for (const double tilt : {-0.2, 0.0, 0.25}) {
        const auto plate = plateAt(thimble, c.z() + pad.radius_m - 0.0015, tilt, -0.5 * tilt);
        ASSERT_TRUE(plate.ok());
        const FeltPadContact felt = user_pad.feel(plate.servo_rad);
        ASSERT_TRUE(felt.pose_known);
        EXPECT_NEAR(felt.indentation_m, deepestSphereSample(c, pad.radius_m, plate.pose), 2e-7);
        // The pressed point lies on the line through the centre along the plate's normal.
        EXPECT_NEAR((felt.point_device_m - c).cross(plate.pose.plateNormal()).norm(), 0.0, 1e-12);
    }
}

TEST(UserPad, TheRetractedPlateAndAPlateBesideThePadFeelNothing) {
    const auto thimble = shippedThimble();
    UserPad user_pad(thimble, shippedPad(), 0.0);
    const tactile::ThimbleKinematics kinematics(thimble);
    const auto retracted = kinematics.inverse(kinematics.retractPose(), false);
    ASSERT_TRUE(retracted.ok());
    const FeltPadContact felt = user_pad.feel(retracted.servo_rad);
    EXPECT_TRUE(felt.pose_known);
    EXPECT_EQ(felt.indentation_m, 0.0);
    EXPECT_EQ(felt.force_device_n, Eigen::Vector3d::Zero());

    // A small plate tilted far enough that the point under the sphere's centre is past its rim.
    config::ThimbleConfig small_plate = thimble;
    small_plate.plate_radius_m = 0.002;
    UserPad beside(small_plate, shippedPad(), 0.0);
    const auto tilted = plateAt(small_plate, beside.firstContactHeightM() - 0.001, 0.35, 0.0);
    ASSERT_TRUE(tilted.ok());
    const FeltPadContact rim = beside.feel(tilted.servo_rad);
    EXPECT_TRUE(rim.pose_known);
    EXPECT_GT((rim.point_device_m - tilted.pose.position_m).norm(), 0.002);
    EXPECT_EQ(rim.force_device_n, Eigen::Vector3d::Zero());
}

TEST(UserPad, AnglesWithNoPoseFeelNothingAndTheNextPoseIsFoundAgain) {
    const auto thimble = shippedThimble();
    UserPad user_pad(thimble, shippedPad(), 0.0);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const FeltPadContact none = user_pad.feel({nan, 0.9, 0.9});
    EXPECT_FALSE(none.pose_known);
    EXPECT_EQ(none.force_device_n, Eigen::Vector3d::Zero());
    const auto plate = plateAt(thimble, user_pad.firstContactHeightM() - 0.001, 0, 0);
    ASSERT_TRUE(plate.ok());
    const FeltPadContact felt = user_pad.feel(plate.servo_rad);
    EXPECT_TRUE(felt.pose_known);
    EXPECT_NEAR(felt.indentation_m, 0.001, 1e-9);
}

// The scene's phalanx (half-length 11.5 mm, longer than the 8 mm plate's radius): a level
// plate meets its side along the disc, as deep as the sphere's and pressing at the middle;
// pitched, the plate meets it nearer one end, as deep as its surface reaches over the disc.
TEST(UserPad, ThePhalanxIsPressedAsDeepAsItsSurfaceReachesOverThePlate) {
    const auto thimble = shippedThimble();
    const auto pad = shippedPad();
    constexpr double kHalf = 0.0115;
    UserPad user_pad(thimble, pad, kHalf);
    const Eigen::Vector3d centre(0.0, 0.0, 0.012);  // -T_finger_device's translation
    ASSERT_TRUE(user_pad.centreDeviceM().isApprox(centre, 1e-15));
    ASSERT_TRUE(user_pad.axisDevice().isApprox(Eigen::Vector3d::UnitX(), 1e-15));
    const double first_contact = user_pad.firstContactHeightM();
    EXPECT_NEAR(first_contact, 0.020, 1e-12);
    {
        // A line load of 50 N/m indents a cylinder by delta = P' / (pi E*) (ln(4 pi E* R / P')
        // - 1); level at that depth, the plate presses the side along its whole 16 mm chord
        // (the tip, 11.5 mm out, lies beyond the 8 mm disc): 0.8 N at the line's middle.
        constexpr double kLineLoad = 50.0;
        const double e_star = pad.effective_modulus_pa;
        const double depth =
            kLineLoad / (std::numbers::pi * e_star) *
            (std::log(4.0 * std::numbers::pi * e_star * pad.radius_m / kLineLoad) - 1.0);
        const auto plate = plateAt(thimble, first_contact - depth, 0.0, 0.0);
        ASSERT_TRUE(plate.ok());
        const FeltPadContact felt = user_pad.feel(plate.servo_rad);
        EXPECT_NEAR(felt.indentation_m, depth, 1e-9);
        EXPECT_NEAR(felt.force_device_n.z(), -kLineLoad * 2.0 * thimble.plate_radius_m, 1e-6);
        EXPECT_NEAR(felt.point_device_m.head<2>().norm(), 0.0, 1e-9) << "the line's middle";
    }
    int pressed = 0;
    double largest_gain_m = 0.0;  // over the sphere at the centre
    double worst_excess_m = 0.0;
    double worst_shortfall_m = 0.0;
    for (const double pitch_deg : {-12.0, -5.0, 3.0, 8.0, 15.0}) {
        for (const double roll_deg : {0.0, 6.0}) {
            for (const double depth : {0.0003, 0.0015}) {
                const double pitch = pitch_deg * std::numbers::pi / 180.0;
                const double roll = roll_deg * std::numbers::pi / 180.0;
                const auto plate = plateAt(thimble, first_contact - depth, roll, pitch);
                ASSERT_TRUE(plate.ok()) << pitch_deg << " " << roll_deg;
                const FeltPadContact felt = user_pad.feel(plate.servo_rad);
                ASSERT_TRUE(felt.pose_known);
                const double expected = std::max(
                    0.0, deepestPhalanxSample(centre, Eigen::Vector3d::UnitX(), kHalf, pad.radius_m,
                                              plate.pose, thimble.plate_radius_m));
                // The model takes the side's line nearest the plate; over the disc's curved rim
                // a point beside that line can reach a little further (measured up to 2.9 um
                // here). The grid's spacing along the axis (5.75 um) lets the sampled surface
                // fall short of the rim by up to 5.75 um x sin(tilt), 1.5 um.
                EXPECT_NEAR(felt.indentation_m, expected, 4e-6)
                    << pitch_deg << " " << roll_deg << " " << depth;
                worst_excess_m = std::max(worst_excess_m, felt.indentation_m - expected);
                worst_shortfall_m = std::max(worst_shortfall_m, expected - felt.indentation_m);
                // The side's line is indented by at most the deepest point's depth along the
                // whole 16 mm chord: no more force than that, and some wherever it is pressed.
                EXPECT_LE(
                    felt.force_device_n.norm(),
                    user_pad.lineLoadAt(felt.indentation_m) * 2.0 * thimble.plate_radius_m + 1e-12);
                EXPECT_EQ(felt.force_device_n.norm() > 0.0, felt.indentation_m > 0.0);
                if (felt.indentation_m > 0.0) {
                    ++pressed;
                    EXPECT_NEAR(felt.force_device_n.normalized().dot(plate.pose.plateNormal()), 1.0,
                                1e-12);
                    EXPECT_NEAR(
                        (felt.point_device_m - plate.pose.position_m).dot(plate.pose.plateNormal()),
                        0.0, 1e-12);
                    EXPECT_LE((felt.point_device_m - plate.pose.position_m).norm(),
                              thimble.plate_radius_m + 1e-12);
                    EXPECT_TRUE(felt.moment_device_nm.isApprox(
                        felt.point_device_m.cross(felt.force_device_n), 1e-12));
                }
                largest_gain_m = std::max(
                    largest_gain_m,
                    felt.indentation_m -
                        std::max(0.0, deepestSphereSample(centre, pad.radius_m, plate.pose)));
            }
        }
    }
    std::printf("against the sampled surface: up to %.2f um deeper, %.2f um shallower\n",
                worst_excess_m * 1e6, worst_shortfall_m * 1e6);
    EXPECT_LE(worst_excess_m, 1.5e-6) << "deeper than the surface reaches";
    EXPECT_GE(pressed, 16);
    // A pitched plate reaches along the phalanx: deeper than a sphere about its centre (1.98 mm
    // at most in these cases, 2026-11-28).
    std::printf("the phalanx pressed up to %.3f mm deeper than a sphere at its centre\n",
                largest_gain_m * 1e3);
    EXPECT_GT(largest_gain_m, 0.0005);
}

// The side's line contact law, checked against its defining relation evaluated forwards:
// the load found for each depth gives that depth back, the load rises with the depth, and it
// goes on (on the secant) past the law's reach at P' = 4 pi E* R / e^2.
TEST(UserPad, TheSidesLineLoadInvertsTheCylindersApproach) {
    const auto pad = shippedPad();
    const UserPad user_pad(shippedThimble(), pad, 0.0115);
    const double e_star = pad.effective_modulus_pa;
    const auto depthOf = [&](double load) {
        return load / (std::numbers::pi * e_star) *
               (std::log(4.0 * std::numbers::pi * e_star * pad.radius_m / load) - 1.0);
    };
    EXPECT_EQ(user_pad.lineLoadAt(0.0), 0.0);
    EXPECT_EQ(user_pad.lineLoadAt(-0.001), 0.0);
    double previous = 0.0;
    for (const double load : {0.1, 1.0, 10.0, 50.0, 200.0, 800.0}) {
        const double depth = depthOf(load);
        EXPECT_NEAR(user_pad.lineLoadAt(depth), load, 1e-6 * load) << load;
        EXPECT_GT(depth, previous);
        previous = depth;
    }
    const double peak_load = 4.0 * std::numbers::pi * e_star * pad.radius_m * std::exp(-2.0);
    const double reach = depthOf(peak_load);
    std::printf("line contact: reach %.2f mm at %.0f N/m\n", reach * 1e3, peak_load);
    EXPECT_NEAR(user_pad.lineLoadAt(reach * (1.0 - 1e-9)), peak_load, 1e-3 * peak_load);
    EXPECT_NEAR(user_pad.lineLoadAt(2.0 * reach), 2.0 * peak_load, 1e-9 * peak_load);
}

// A phalanx short enough (half-length 4 mm) for its tip to lie over the disc: a level plate
// presses the side's 8 mm line and half the tip's contact circle (the other half is the
// side's), and pitching the plate a little either way changes the force a little: the tip's
// share moves continuously between the side and the cap.
TEST(UserPad, TheTipCarriesItsShareOfTheContactCircleAndTheForceIsContinuousInPitch) {
    const auto thimble = shippedThimble();
    const auto pad = shippedPad();
    constexpr double kHalf = 0.004;
    constexpr double kDepth = 0.001;
    UserPad user_pad(thimble, pad, kHalf);
    const double first_contact = user_pad.firstContactHeightM();
    const auto level = plateAt(thimble, first_contact - kDepth, 0.0, 0.0);
    ASSERT_TRUE(level.ok());
    const double level_force = user_pad.feel(level.servo_rad).force_device_n.norm();
    const double hertz =
        4.0 / 3.0 * pad.effective_modulus_pa * std::sqrt(pad.radius_m) * std::pow(kDepth, 1.5);
    EXPECT_NEAR(level_force, 2.0 * kHalf * user_pad.lineLoadAt(kDepth) + 0.5 * hertz, 1e-9);
    for (const double pitch_deg : {-0.2, 0.2}) {
        const auto pitched =
            plateAt(thimble, first_contact - kDepth, 0.0, pitch_deg * std::numbers::pi / 180.0);
        ASSERT_TRUE(pitched.ok());
        const double force = user_pad.feel(pitched.servo_rad).force_device_n.norm();
        EXPECT_NEAR(force, level_force, 0.05 * level_force) << pitch_deg;
    }
}

TEST(UserPad, ANegativeHalfLengthIsRefused) {
    EXPECT_THROW(UserPad(shippedThimble(), shippedPad(), -0.001), std::invalid_argument);
}

}  // namespace
}  // namespace haptic::emu
