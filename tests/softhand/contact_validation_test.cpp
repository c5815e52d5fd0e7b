// Contact validation against closed forms: Hertz indentation and Coulomb stick/slip.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "haptic/softhand/simulation.hpp"
#include "validation_support.hpp"

namespace haptic::softhand {
namespace {

constexpr double kKineticTolerance = 0.15;

class SofthandContactValidation : public ::testing::TestWithParam<SolverProfile> {};

// Rigid sphere pressed into an elastic block: F = 4/3 E/(1 - nu^2) sqrt(R) d^1.5. Linear
// tetrahedra are stiff, so this coarse mesh gets 25%; softhand_fine_test checks 10%.
TEST_P(SofthandContactValidation, HertzCoarseMeshFollowsHertzWithin25Percent) {
    for (double indentation : {0.2e-3, 0.4e-3}) {
        const double ratio = hertzForceRatio(8, 1.45, 0.02, indentation, GetParam());
        std::printf("%s: F / F_Hertz %.4f at %.1f mm\n", profileName(GetParam()).c_str(), ratio,
                    1e3 * indentation);
        EXPECT_NEAR(ratio, 1.0, 0.25) << "indentation " << indentation;
        if (GetParam() == SolverProfile::kShipped) {
            // As shipped, within 2 % of the converged solve of the same mesh.
            const double converged = hertzForceRatio(8, 1.45, 0.02, indentation);
            EXPECT_NEAR(ratio, converged, 0.02 * converged) << "indentation " << indentation;
        }
    }
}

// A soft block on an incline with friction mu, released and settled onto it. Returns the
// centroid's positions along the downhill direction at `times_s` after the settling.
std::vector<double> downhillPositions(double incline_rad, double mu, SolverProfile profile,
                                      const std::vector<double>& times_s) {
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = 200.0;
    settings.friction_stiffness_n_per_m = 200.0;
    settings.mass_damping_per_s = 0.0;
    Simulation sim(withProfile(settings, profile));
    TissueMaterial material;
    material.youngs_modulus_pa = 5.0e4;
    material.density_kg_per_m3 = 1000.0;
    const double side = 0.01;
    TetMesh mesh =
        makeBoxMesh(Vec3(-side / 2, -side / 2, 0.0), Vec3(side / 2, side / 2, side), {3, 3, 3});
    const Mat3 tilt = Eigen::AngleAxisd(incline_rad, Vec3::UnitY()).toRotationMatrix();
    for (auto& p : mesh.nodes_m) {
        p = tilt * p;
    }
    sim.addTissue(mesh, material);
    sim.addCollider({HalfSpace{}, Vec3::Zero(), tilt, mu});
    const Vec3 downhill = tilt * Vec3(1.0, 0.0, 0.0);
    const auto centroid = [&] {
        Vec3 c = Vec3::Zero();
        for (int i = 0; i < sim.nodeCount(); ++i) {
            c += sim.nodePosition(i);
        }
        return Vec3(c / sim.nodeCount());
    };
    constexpr double kDt = 0.005;
    for (int s = 0; s < 40; ++s) {  // settle onto the plane
        sim.step(kDt);
    }
    const Vec3 start = centroid();
    std::vector<double> out;
    int step = 0;
    for (double t : times_s) {
        for (; step < static_cast<int>(std::lround(t / kDt)); ++step) {
            sim.step(kDt);
        }
        out.push_back((centroid() - start).dot(downhill));
    }
    return out;
}

TEST_P(SofthandContactValidation, StickSlipSwitchesAtTheFrictionAngle) {
    const double mu = 0.5;
    const double friction_angle = std::atan(mu);
    const double margin = 2.0 * std::numbers::pi / 180.0;
    const double stick = downhillPositions(friction_angle - margin, mu, GetParam(), {0.5})[0];
    const double slip = downhillPositions(friction_angle + margin, mu, GetParam(), {0.5})[0];
    std::printf("%s: %.3f mm in 0.5 s at 2 deg below the friction angle, %.3f mm above\n",
                profileName(GetParam()).c_str(), 1e3 * stick, 1e3 * slip);
    // Sliding at the margin accelerates at g (sin - mu cos) ~ 0.38 m/s^2: ~2 cm in 0.5 s.
    EXPECT_LT(std::abs(stick), 0.5e-3);
    EXPECT_GT(slip, 5.0e-3);
}

// Kinetic Coulomb law: a sliding block accelerates at g (sin a - mu cos a). The acceleration is
// the second difference of three positions T apart once sliding, which does not depend on
// the speed the block had when the measurement began.
TEST_P(SofthandContactValidation, SlidingBlockAcceleratesAtTheKineticCoulombRate) {
    const double mu = 0.5;
    const double incline = std::atan(mu) + 10.0 * std::numbers::pi / 180.0;
    constexpr double kGap = 0.1;
    const std::vector<double> x = downhillPositions(incline, mu, GetParam(), {0.1, 0.2, 0.3});
    const double measured = (x[2] - 2.0 * x[1] + x[0]) / (kGap * kGap);
    const double coulomb = 9.81 * (std::sin(incline) - mu * std::cos(incline));
    std::printf("%s: acceleration %.3f m/s^2, Coulomb %.3f m/s^2\n",
                profileName(GetParam()).c_str(), measured, coulomb);
    if (GetParam() == SolverProfile::kConverged) {
        EXPECT_NEAR(measured, coulomb, kKineticTolerance * coulomb);
    } else {
        // As shipped the block slides at about a third of the Coulomb rate (0.61 against
        // 1.90 m/s^2 on 2026-11-27): a free soft body's rigid translation is the slowest mode
        // for block-Jacobi PCG, and 30 iterations move it only part of the way each step. In
        // the hand scenes the bones carry the rigid modes. The band says what ships: it slides,
        // downhill, and never faster than Coulomb allows; docs/benchmarks.md has the figures.
        EXPECT_GT(measured, 0.25 * coulomb);
        EXPECT_LT(measured, (1.0 + kKineticTolerance) * coulomb);
    }
}

INSTANTIATE_TEST_SUITE_P(BothSettings, SofthandContactValidation,
                         ::testing::Values(SolverProfile::kConverged, SolverProfile::kShipped),
                         [](const ::testing::TestParamInfo<SolverProfile>& info) {
                             return profileName(info.param);
                         });

}  // namespace
}  // namespace haptic::softhand
