#include "haptic/tactile/contact_optimiser.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "allocation_counter.hpp"
#include "haptic/config/device.hpp"
#include "haptic/tactile/baselines.hpp"
#include "haptic/tactile/fingertip_model.hpp"

namespace haptic::tactile {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

config::ThimbleConfig shippedThimble() {
    return config::loadDeviceConfig(HAPTIC_THIMBLE_CONFIG).thimble();
}

bool allFinite(const TactileCommand& c) {
    return std::isfinite(c.servo_rad[0]) && std::isfinite(c.servo_rad[1]) &&
           std::isfinite(c.servo_rad[2]) && std::isfinite(c.dofs.height_m) &&
           std::isfinite(c.dofs.tilt_x_rad) && std::isfinite(c.dofs.tilt_y_rad);
}

class ContactOptimiserTest : public ::testing::Test {
  protected:
    config::ThimbleConfig config{shippedThimble()};
    ThimbleKinematics kinematics{config};
    NonlinearPadModel pad{PadModelParameters{}};
    ContactSurfaceOptimiser sut{kinematics, OptimiserSettings::fromConfig(config)};

    // A plane pressed depth_m into the pad, tilted by angle_rad about y.
    msgs::ContactSurface planeSurface(double angle_rad, double depth_m,
                                      Eigen::Vector3d* outward = nullptr) const {
        const auto& p = pad.parameters();
        const Eigen::Vector3d centre(0.0, 0.0, p.contact_height_m - p.pad_radius_m);
        const Eigen::Vector3d n(-std::sin(angle_rad), 0.0, -std::cos(angle_rad));
        if (outward != nullptr) {
            *outward = n;
        }
        const HalfSpaceObstacle plane(centre - (p.pad_radius_m - depth_m) * n, n);
        return pad.contactSurface(plane, config.optimiser.pad_samples, SampleWeighting::kArea);
    }

    // A 6 mm sphere 1.5 mm into the pad, slightly off-centre: no plane matches it exactly.
    msgs::ContactSurface sphereSurface() const {
        return pad.contactSurface(SphereObstacle(Eigen::Vector3d(0.001, 0.0, 0.0225), 0.006),
                                  config.optimiser.pad_samples, SampleWeighting::kContactStiffness);
    }

    void expectInsideWorkspace(const TactileCommand& command) const {
        EXPECT_TRUE(allFinite(command));
        const InverseResult ik = kinematics.inverse(command.dofs);
        ASSERT_TRUE(ik.ok()) << toString(ik.error);
        for (std::size_t i = 0; i < 3; ++i) {
            EXPECT_NEAR(command.servo_rad[i], ik.servo_rad[i], 1e-12);
        }
    }
};

TEST_F(ContactOptimiserTest, ReachablePlaneIsMatchedExactly) {
    Eigen::Vector3d outward;
    const auto command = sut.solve(planeSurface(0.15, 0.0015, &outward));
    EXPECT_EQ(command.report.outcome, SolveOutcome::kMatched);
    EXPECT_TRUE(command.report.converged);
    EXPECT_FALSE(command.report.clamped);
    EXPECT_FALSE(command.report.poor_match);
    EXPECT_LT(command.report.contact_rms_m, 1e-6);
    EXPECT_GT(command.pose.plateNormal().dot(outward), std::cos(1e-4));
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, WarmStartConvergesAtOnceOnAnUnchangedSurface) {
    const auto surface = sphereSurface();
    const auto first = sut.solve(surface);
    const auto second = sut.solve(surface);
    EXPECT_LE(second.report.iterations, 2);
    EXPECT_LT(second.report.iterations, first.report.iterations);
    EXPECT_NEAR(second.dofs.height_m, first.dofs.height_m, 1e-7);
    EXPECT_NEAR(second.dofs.tilt_x_rad, first.dofs.tilt_x_rad, 1e-5);
}

TEST_F(ContactOptimiserTest, EmptySurfaceRetracts) {
    (void)sut.solve(planeSurface(0.0, 0.001));
    const auto command = sut.solve(msgs::ContactSurface{});
    EXPECT_EQ(command.report.outcome, SolveOutcome::kRetractedNoContact);
    EXPECT_EQ(command.dofs.height_m, kinematics.retractPose().height_m);
    EXPECT_EQ(command.dofs.tilt_x_rad, 0.0);
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, SurfaceWithoutContactRetracts) {
    const auto command = sut.solve(planeSurface(0.0, -0.002));  // plane 2 mm short of the pad
    EXPECT_EQ(command.report.outcome, SolveOutcome::kRetractedNoContact);
    EXPECT_EQ(command.dofs.height_m, kinematics.retractPose().height_m);
}

TEST_F(ContactOptimiserTest, AllSamplesInContactStillMatches) {
    // A flat patch of 64 samples at z = 17 mm, every one 0.5 mm inside an object whose
    // surface (outward normal -z) is therefore at z = 16.5 mm.
    msgs::ContactSurface surface;
    for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) {
            msgs::ContactSample s;
            s.p_device_m = {-0.0035 + 0.001 * i, -0.0035 + 0.001 * j, 0.017};
            s.signed_distance_m = -0.0005;
            s.normal_device = {0.0, 0.0, -1.0};
            s.weight = 1e-6;
            surface.samples.push_back(s);
        }
    }
    const auto command = sut.solve(surface);
    EXPECT_EQ(command.report.outcome, SolveOutcome::kMatched);
    EXPECT_TRUE(command.report.converged);
    EXPECT_FALSE(command.report.clamped);
    EXPECT_NEAR(command.pose.position_m.z(), 0.0165, 1e-7);
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, TargetBeyondTheTiltLimitEndsClampedWithFlags) {
    const auto command = sut.solve(planeSurface(0.8, 0.0015));  // 46 degrees
    EXPECT_EQ(command.report.outcome, SolveOutcome::kMatched);
    EXPECT_TRUE(command.report.clamped);
    EXPECT_NE(command.report.active_constraints, 0U);
    EXPECT_TRUE(command.report.poor_match);
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, TargetBeyondTheIndentationLimitStopsAtTheLimit) {
    const auto command = sut.solve(planeSurface(0.0, 0.006));
    EXPECT_TRUE(command.report.clamped);
    EXPECT_TRUE(command.report.active_constraints &
                (1U << static_cast<int>(Constraint::kIndentation)));
    EXPECT_NEAR(command.dofs.height_m, kinematics.minHeightM(), 1e-5);
    EXPECT_GE(command.dofs.height_m, kinematics.minHeightM());
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, ContradictorySamplesGiveAFeasibleCompromiseAndAFlag) {
    // The same pad points claimed by two objects 1 mm apart, one of them pushing from the
    // nail side.
    msgs::ContactSurface surface = planeSurface(0.0, 0.0015);
    const std::uint32_t n = surface.samples.count;
    for (std::uint32_t i = 0; i < n && !surface.samples.full(); ++i) {
        msgs::ContactSample s = surface.samples[i];
        if (s.signed_distance_m < 0.0) {
            s.signed_distance_m -= 0.001;
            s.normal_device = {0.0, 0.0, 1.0};
            surface.samples.push_back(s);
        }
    }
    auto settings = OptimiserSettings::fromConfig(config);
    settings.max_samples = static_cast<int>(msgs::kMaxContactSamples);
    ContactSurfaceOptimiser optimiser(kinematics, settings);
    const auto command = optimiser.solve(surface);
    EXPECT_EQ(command.report.outcome, SolveOutcome::kMatched);
    EXPECT_TRUE(command.report.poor_match);
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, NaNAndOutOfFrameSamplesAreRejectedWithAReason) {
    struct Corruption {
        void (*apply)(msgs::ContactSample&);
        InputError expected;
    };
    const Corruption corruptions[] = {
        {[](msgs::ContactSample& s) { s.p_device_m[1] = kNaN; }, InputError::kNonFinitePosition},
        {[](msgs::ContactSample& s) { s.signed_distance_m = kNaN; },
         InputError::kNonFiniteDistance},
        {[](msgs::ContactSample& s) { s.normal_device[2] = kNaN; }, InputError::kNonFiniteNormal},
        {[](msgs::ContactSample& s) { s.weight = std::numeric_limits<double>::infinity(); },
         InputError::kNonFiniteWeight},
        {[](msgs::ContactSample& s) { s.weight = -1.0; }, InputError::kNegativeWeight},
        {[](msgs::ContactSample& s) { s.p_device_m[0] = 0.2; }, InputError::kOutOfFrame},
        {[](msgs::ContactSample& s) {
             s.signed_distance_m = -0.001;
             s.normal_device = {0.0, 0.0, -2.0};
         },
         InputError::kNormalNotUnit},
    };
    for (const Corruption& corruption : corruptions) {
        (void)sut.solve(planeSurface(0.0, 0.001));  // leave the retract pose first
        msgs::ContactSurface surface = planeSurface(0.0, 0.001);
        corruption.apply(surface.samples[17]);
        const auto command = sut.solve(surface);
        EXPECT_EQ(command.report.outcome, SolveOutcome::kRejectedInput);
        EXPECT_EQ(command.report.input.error, corruption.expected)
            << toString(command.report.input.error);
        EXPECT_EQ(command.report.input.sample_index, 17);
        EXPECT_EQ(command.dofs.height_m, kinematics.retractPose().height_m);
        expectInsideWorkspace(command);
    }
}

TEST_F(ContactOptimiserTest, MoreSamplesThanConfiguredAreRejected) {
    msgs::ContactSurface surface = planeSurface(0.0, 0.001);
    surface.samples.push_back(surface.samples[0]);
    const auto command = sut.solve(surface);
    EXPECT_EQ(command.report.input.error, InputError::kTooManySamples);
    EXPECT_EQ(command.report.outcome, SolveOutcome::kRejectedInput);
}

// optimiser.pad_samples at 16 (shipped 64), through the mapping hapticd uses: a surface of
// the shipped size is refused, one of 16 samples is solved.
TEST_F(ContactOptimiserTest, TheSampleBoundIsTheDeviceFilesPadSamples) {
    auto sixteen = config;
    sixteen.optimiser.pad_samples = 16;
    ContactSurfaceOptimiser bounded(kinematics, OptimiserSettings::fromConfig(sixteen));
    const msgs::ContactSurface shipped_size = planeSurface(0.0, 0.001);
    ASSERT_EQ(shipped_size.samples.size(), 64U);
    EXPECT_EQ(bounded.solve(shipped_size).report.input.error, InputError::kTooManySamples);
    EXPECT_EQ(sut.solve(shipped_size).report.input.error, InputError::kNone);
    const HalfSpaceObstacle plane(
        Eigen::Vector3d(0.0, 0.0, pad.parameters().contact_height_m - 0.001),
        Eigen::Vector3d(0.0, 0.0, -1.0));
    const msgs::ContactSurface small = pad.contactSurface(plane, 16, SampleWeighting::kArea);
    ASSERT_EQ(small.samples.size(), 16U);
    const auto command = bounded.solve(small);
    EXPECT_EQ(command.report.input.error, InputError::kNone);
    EXPECT_EQ(command.report.outcome, SolveOutcome::kMatched);
}

// optimiser.pad_stiffening_depth_m, through the mapping hapticd uses: the pad law the plate's
// force balance assumes. On a sphere no plane matches, so where the plate settles depends on
// how the pad stiffens: the shipped near-linear law (0.1 m) and a strongly stiffening one
// (2 mm) put it at different heights.
TEST_F(ContactOptimiserTest, TheStiffeningDepthKeyDecidesWhereThePlateSettles) {
    auto stiffening = config;
    stiffening.optimiser.pad_stiffening_depth_m = 0.002;
    ASSERT_GT(config.optimiser.pad_stiffening_depth_m, 0.05) << "the shipped law changed";
    ContactSurfaceOptimiser other(kinematics, OptimiserSettings::fromConfig(stiffening));
    const auto surface = sphereSurface();
    const auto shipped = sut.solve(surface);
    const auto stiffer = other.solve(surface);
    ASSERT_TRUE(shipped.report.converged);
    ASSERT_TRUE(stiffer.report.converged);
    std::printf("plate height: shipped law %.4f mm, 2 mm stiffening %.4f mm\n",
                shipped.dofs.height_m * 1e3, stiffer.dofs.height_m * 1e3);
    EXPECT_GT(std::abs(shipped.dofs.height_m - stiffer.dofs.height_m), 1e-5);
    expectInsideWorkspace(stiffer);
}

TEST_F(ContactOptimiserTest, IterationsNeverExceedTheConfiguredBound) {
    // optimiser.max_iterations in the device file, through the mapping hapticd uses.
    auto one_iteration = config;
    one_iteration.optimiser.max_iterations = 1;
    const auto settings = OptimiserSettings::fromConfig(one_iteration);
    ContactSurfaceOptimiser one_step(kinematics, settings);
    const auto command = one_step.solve(sphereSurface());
    EXPECT_EQ(command.report.iterations, 1);
    EXPECT_FALSE(command.report.converged);
    expectInsideWorkspace(command);
}

TEST_F(ContactOptimiserTest, SolveDoesNotAllocate) {
    const auto sphere_surface = sphereSurface();
    const auto plane_surface = planeSurface(0.2, 0.0015);
    const msgs::ContactSurface empty{};
    testing::ScopedAllocationCounter counter;
    for (int i = 0; i < 20; ++i) {
        (void)sut.solve(i % 3 == 0 ? sphere_surface : i % 3 == 1 ? plane_surface : empty);
    }
    EXPECT_EQ(counter.allocations(), 0U);
}

TEST_F(ContactOptimiserTest, GeometricBaselineLandsOnAReachablePlane) {
    Eigen::Vector3d outward;
    const auto surface = planeSurface(0.1, 0.001, &outward);
    const auto dofs = geometricPlaneFit(kinematics, surface);
    ASSERT_TRUE(dofs.has_value());
    const InverseResult ik = kinematics.inverse(*dofs);
    ASSERT_TRUE(ik.ok());
    EXPECT_NEAR(ik.pose.plateNormal().dot(outward), 1.0, 1e-12);
    EXPECT_FALSE(geometricPlaneFit(kinematics, msgs::ContactSurface{}).has_value());
}

TEST_F(ContactOptimiserTest, ForceBaselinePressesAlongTheForceByForceOverStiffness) {
    const auto surface = planeSurface(0.0, 0.001);
    const auto dofs =
        forceNormalDisplacement(kinematics, surface, Eigen::Vector3d(0.0, 0.0, -0.2), 200.0);
    ASSERT_TRUE(dofs.has_value());
    // First touch at the lowest sample, then 0.2 N / 200 N/m = 1 mm towards the nail.
    double lowest = 0.0;
    for (const auto& s : surface.samples) {
        lowest = std::max(lowest, s.p_device_m[2]);
    }
    EXPECT_NEAR(dofs->height_m, lowest - 0.001, 1e-9);
    EXPECT_FALSE(forceNormalDisplacement(kinematics, surface, Eigen::Vector3d::Zero(), 200.0));
}

TEST(NonlinearPadModelTest, FlatPlateForceStiffensWithDepth) {
    const NonlinearPadModel pad{PadModelParameters{}};
    EXPECT_EQ(pad.flatPlateForce(0.0), 0.0);
    const double f1 = pad.flatPlateForce(0.001);
    const double f2 = pad.flatPlateForce(0.002);
    EXPECT_NEAR(f2, 1.0, 0.05);  // the documented calibration point
    EXPECT_GT(f2 - f1, f1);      // stiffening: the second millimetre costs more than the first
}

}  // namespace
}  // namespace haptic::tactile
