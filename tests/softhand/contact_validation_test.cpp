// Contact validation against closed forms: Hertz indentation and Coulomb stick/slip.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "haptic/softhand/simulation.hpp"
#include "validation_support.hpp"

namespace haptic::softhand {
namespace {

// Rigid sphere pressed into an elastic block: F = 4/3 E/(1 - nu^2) sqrt(R) d^1.5. Linear
// tetrahedra are stiff, so this coarse mesh gets 25%; softhand_fine_test checks 10%.
TEST(SofthandHertz, CoarseMeshFollowsHertzWithin25Percent) {
    for (double indentation : {0.2e-3, 0.4e-3}) {
        EXPECT_NEAR(hertzForceRatio(8, 1.45, 0.02, indentation), 1.0, 0.25)
            << "indentation " << indentation;
    }
}

// A soft block on an incline with friction mu sticks below atan(mu) and slides above it.
double slideDistance(double incline_rad, double mu) {
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = 200.0;
    settings.friction_stiffness_n_per_m = 200.0;
    settings.mass_damping_per_s = 0.0;
    Simulation sim(settings);
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
    // Settle onto the plane first, then measure from the settled position.
    for (int s = 0; s < 40; ++s) {
        sim.step(0.005);
    }
    const Vec3 start = centroid();
    for (int s = 0; s < 100; ++s) {
        sim.step(0.005);
    }
    return (centroid() - start).dot(downhill);
}

TEST(SofthandFriction, StickSlipSwitchesAtTheFrictionAngle) {
    const double mu = 0.5;
    const double friction_angle = std::atan(mu);
    const double margin = 2.0 * std::numbers::pi / 180.0;
    const double stick = slideDistance(friction_angle - margin, mu);
    const double slip = slideDistance(friction_angle + margin, mu);
    // Sliding at the margin accelerates at g (sin - mu cos) ~ 0.38 m/s^2: ~2 cm in 0.5 s.
    EXPECT_LT(std::abs(stick), 0.5e-3);
    EXPECT_GT(slip, 5.0e-3);
}

}  // namespace
}  // namespace haptic::softhand
