// Validation of the tissue and skeleton energies against closed-form references computed
// here: the patch test, Euler-Bernoulli cantilever, and soft-joint sag. Each runs at converged
// settings and at handsim's shipped real-time limits (validation_support.hpp), with the
// tolerance each states.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "haptic/softhand/simulation.hpp"
#include "validation_support.hpp"

namespace haptic::softhand {
namespace {

constexpr double kPatchTolerance_m = 1e-9;

SolverSettings staticSettings() {
    SolverSettings s;
    s.gravity_m_per_s2 = Vec3::Zero();
    s.pcg_max_iterations = 4000;
    s.pcg_relative_tolerance = 1e-10;
    s.mass_damping_per_s = 0.0;
    s.stiffness_damping_s = 0.0;
    return s;
}

TissueMaterial linearMaterial(double youngs_pa, double poisson) {
    TissueMaterial m;
    m.youngs_modulus_pa = youngs_pa;
    m.poisson_ratio = poisson;
    m.strain_limits = false;
    return m;
}

bool onBoundary(const Vec3& p, const Vec3& lo, const Vec3& hi) {
    for (int a = 0; a < 3; ++a) {
        if (std::abs(p[a] - lo[a]) < 1e-12 || std::abs(p[a] - hi[a]) < 1e-12) {
            return true;
        }
    }
    return false;
}

// Patch test: an affine field imposed on the boundary must be reproduced exactly inside,
// also under a large rigid rotation (the co-rotation must factor it out).
void expectPatchTestPasses(const Mat3& deformation, SolverProfile profile, double tolerance_m) {
    const Vec3 lo(0.0, 0.0, 0.0);
    const Vec3 hi(0.01, 0.012, 0.009);
    // Irregular interior: perturb the grid so the elements are not all alike.
    TetMesh mesh = makeGridMesh({0.0, 0.003, 0.0055, 0.01}, {0.0, 0.005, 0.007, 0.012},
                                {0.0, 0.002, 0.006, 0.009});
    Simulation sim(withProfile(staticSettings(), profile));
    sim.addTissue(mesh, linearMaterial(1.0e5, 0.3));
    const Vec3 offset(0.002, -0.001, 0.003);
    int interior = 0;
    for (int i = 0; i < sim.nodeCount(); ++i) {
        const Vec3 rest = sim.nodeRestPosition(i);
        if (onBoundary(rest, lo, hi)) {
            sim.setNodePosition(i, deformation * rest + offset);
            sim.pinNode(i);
        } else {
            ++interior;
        }
    }
    ASSERT_GT(interior, 0);
    sim.relax(1.0, relaxSteps(50, profile), 1e-12);
    for (int i = 0; i < sim.nodeCount(); ++i) {
        const Vec3 expected = deformation * sim.nodeRestPosition(i) + offset;
        EXPECT_LT((sim.nodePosition(i) - expected).norm(), tolerance_m) << "node " << i;
    }
}

class SofthandValidation : public ::testing::TestWithParam<SolverProfile> {};

std::string profileParamName(const ::testing::TestParamInfo<SolverProfile>& info) {
    return profileName(info.param);
}

// The patch tolerance is 1 nm at both settings: the shipped relaxation takes 40x the steps,
// and its capped PCG steps reach the affine field as closely as the converged ones.
double patchTolerance(SolverProfile /*profile*/) {
    return kPatchTolerance_m;
}

TEST_P(SofthandValidation, PatchTestAffineStretchIsReproducedInside) {
    Mat3 stretch;
    stretch << 1.02, 0.01, 0.0, 0.005, 0.99, 0.01, 0.0, -0.01, 1.01;
    expectPatchTestPasses(stretch, GetParam(), patchTolerance(GetParam()));
}

TEST_P(SofthandValidation, PatchTestAffineStretchUnderLargeRotationIsReproducedInside) {
    Mat3 stretch;
    stretch << 1.02, 0.01, 0.0, 0.01, 0.99, 0.0, 0.0, 0.0, 1.01;
    const Mat3 rotation = expMap(Vec3(0.4, -0.9, 0.7));
    expectPatchTestPasses(rotation * stretch, GetParam(), patchTolerance(GetParam()));
}

TEST_P(SofthandValidation, CantileverConvergesTowardsEulerBernoulliFromTheStiffSide) {
    // Linear tetrahedra lock in bending, so coarse meshes are stiff; the 5% check at a fine
    // resolution is softhand_fine_test (Release only). Here: monotone approach from below.
    const double coarse = cantileverTipDeflectionRatio({10, 2, 2}, GetParam());
    const double finer = cantileverTipDeflectionRatio({20, 3, 3}, GetParam());
    std::printf("%s: tip deflection / Euler-Bernoulli %.4f (10x2x2), %.4f (20x3x3)\n",
                profileName(GetParam()).c_str(), coarse, finer);
    EXPECT_GT(coarse, 0.2);
    EXPECT_LT(coarse, finer);
    EXPECT_LT(finer, 1.0);
    if (GetParam() == SolverProfile::kShipped) {
        // Against the converged solve of the same mesh: the shipped relaxation is stated to
        // reach within 10 % of it (0.584 against 0.620 at 20x3x3 on 2026-11-27).
        EXPECT_NEAR(coarse, cantileverTipDeflectionRatio({10, 2, 2}), 0.10 * coarse);
        const double converged = cantileverTipDeflectionRatio({20, 3, 3});
        EXPECT_NEAR(finer, converged, 0.10 * converged);
    }
}

TEST_P(SofthandValidation, SoftBallJointSagsByWeightOverStiffness) {
    SolverSettings settings = staticSettings();
    settings.gravity_m_per_s2 = Vec3(0.0, 0.0, -9.81);
    Simulation sim(withProfile(settings, GetParam()));
    RigidBodyDesc anchor;
    anchor.kinematic = true;
    const int a = sim.addBody(anchor);
    RigidBodyDesc hanging;
    hanging.mass_kg = 0.02;
    hanging.position_m = Vec3(0.03, 0.0, 0.0);
    const int b = sim.addBody(hanging);
    JointDesc joint;
    joint.type = JointType::kHinge;
    joint.body_a = a;
    joint.body_b = b;
    joint.anchor_world_m = hanging.position_m;
    joint.positional_stiffness_n_per_m = 500.0;
    joint.alignment_stiffness_nm_per_rad = 0.5;
    sim.addJoint(joint);
    sim.relax(1.0, relaxSteps(50, GetParam()), 1e-12);
    const double expected = hanging.mass_kg * 9.81 / joint.positional_stiffness_n_per_m;
    const double sag = hanging.position_m.z() - sim.bodyPosition(b).z();
    std::printf("%s: sag %.6f mm, weight/stiffness %.6f mm\n", profileName(GetParam()).c_str(),
                1e3 * sag, 1e3 * expected);
    EXPECT_NEAR(sag, expected, 0.01 * expected);
    EXPECT_NEAR(sim.bodyPosition(b).x(), hanging.position_m.x(), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(BothSettings, SofthandValidation,
                         ::testing::Values(SolverProfile::kConverged, SolverProfile::kShipped),
                         profileParamName);

TEST(SofthandJoint, HingeLimitStopsFlexionAtTheLimit) {
    // The hinge is free inside its limits, so this one is dynamic: the bar falls onto the
    // limit and damping settles it there.
    SolverSettings settings;
    settings.mass_damping_per_s = 20.0;
    Simulation sim(settings);
    RigidBodyDesc anchor;
    anchor.kinematic = true;
    const int a = sim.addBody(anchor);
    // A phalanx-like bar hinged at its end about y: gravity flexes it down (positive about y).
    RigidBodyDesc bar;
    bar.mass_kg = 0.01;
    bar.position_m = Vec3(0.02, 0.0, 0.0);
    bar.inertia_body_kg_m2 = Vec3(1e-7, 1.3e-6, 1.3e-6).asDiagonal();
    const int b = sim.addBody(bar);
    JointDesc joint;
    joint.type = JointType::kHinge;
    joint.body_a = a;
    joint.body_b = b;
    joint.anchor_world_m = Vec3::Zero();
    joint.axis_world = Vec3::UnitY();
    joint.positional_stiffness_n_per_m = 2.0e4;
    joint.alignment_stiffness_nm_per_rad = 1.0;
    joint.limit_min_rad = -0.1;
    joint.limit_max_rad = 0.3;
    joint.limit_stiffness_nm_per_rad = 50.0;
    sim.addJoint(joint);
    for (int s = 0; s < 600; ++s) {
        sim.step(0.005);
    }
    const Vec3 theta = logMap(sim.bodyRotation(b));
    // Torque m g l cos(phi) held by the limit spring: phi = max + m g l cos(phi) / k_lim.
    const double torque = bar.mass_kg * 9.81 * 0.02 * std::cos(0.3);
    EXPECT_NEAR(theta.y(), 0.3 + torque / joint.limit_stiffness_nm_per_rad, 2e-3);
    EXPECT_NEAR(theta.x(), 0.0, 1e-6);
    EXPECT_NEAR(theta.z(), 0.0, 1e-6);
}

}  // namespace
}  // namespace haptic::softhand
