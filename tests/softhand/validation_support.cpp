#include "validation_support.hpp"

#include <cmath>
#include <vector>

#include "haptic/softhand/scene_simulation.hpp"
#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand {

SolverSettings withProfile(SolverSettings settings, SolverProfile profile) {
    return profile == SolverProfile::kShipped ? withRealtimeLimits(settings) : settings;
}

int relaxSteps(int converged, SolverProfile profile) {
    return profile == SolverProfile::kShipped ? 40 * converged : converged;
}

std::string profileName(SolverProfile profile) {
    return profile == SolverProfile::kShipped ? "Shipped" : "Converged";
}

namespace {

SolverSettings staticSettings() {
    SolverSettings s;
    s.gravity_m_per_s2 = Vec3::Zero();
    s.pcg_max_iterations = 20000;
    s.pcg_relative_tolerance = 1e-9;
    s.mass_damping_per_s = 0.0;
    s.stiffness_damping_s = 0.0;
    return s;
}

}  // namespace

double cantileverTipDeflectionRatio(std::array<int, 3> cells, SolverProfile profile) {
    const double length = 0.1;
    const double side = 0.01;
    const double youngs = 1.0e6;
    const double load = 0.0025;  // EB tip deflection 1 mm: small-deflection regime
    Simulation sim(withProfile(staticSettings(), profile));
    TissueMaterial material;
    material.youngs_modulus_pa = youngs;
    material.poisson_ratio = 0.3;
    material.strain_limits = false;
    sim.addTissue(makeBoxMesh(Vec3(0.0, 0.0, 0.0), Vec3(length, side, side), cells), material);
    std::vector<int> tip;
    for (int i = 0; i < sim.nodeCount(); ++i) {
        const Vec3& p = sim.nodeRestPosition(i);
        if (p.x() < 1e-12) {
            sim.pinNode(i);
        } else if (p.x() > length - 1e-12) {
            tip.push_back(i);
        }
    }
    // Consistent nodal loads of a uniform traction on a regular grid face: corner 1, edge 2,
    // interior 4 (in quarter cell areas).
    std::vector<double> weights;
    double weight_sum = 0.0;
    for (int i : tip) {
        const Vec3& p = sim.nodeRestPosition(i);
        const bool y_edge = p.y() < 1e-12 || p.y() > side - 1e-12;
        const bool z_edge = p.z() < 1e-12 || p.z() > side - 1e-12;
        weights.push_back((y_edge ? 1.0 : 2.0) * (z_edge ? 1.0 : 2.0));
        weight_sum += weights.back();
    }
    for (std::size_t k = 0; k < tip.size(); ++k) {
        sim.setNodeForce(tip[k], Vec3(0.0, 0.0, -load * weights[k] / weight_sum));
    }
    sim.relax(1.0, relaxSteps(20, profile), 1e-10);
    double tip_z = 0.0;
    for (int i : tip) {
        tip_z += sim.nodePosition(i).z() - sim.nodeRestPosition(i).z();
    }
    const double inertia = side * side * side * side / 12.0;
    const double euler_bernoulli = load * length * length * length / (3.0 * youngs * inertia);
    return -tip_z / static_cast<double>(tip.size()) / euler_bernoulli;
}

double hertzForceRatio(int cells, double grading, double width_m, double indentation_m,
                       SolverProfile profile) {
    const double youngs = 1.0e5;
    const double poisson = 0.3;
    const double radius = 0.01;
    SolverSettings settings = staticSettings();
    settings.pcg_relative_tolerance = 1e-7;
    // Per-node penalty: at these forces the penetration is < 1 um against d >= 100 um.
    settings.contact_stiffness_n_per_m = 2.0e4;
    settings.friction_stiffness_n_per_m = 0.0;  // Hertz is frictionless
    Simulation sim(withProfile(settings, profile));
    const auto lateral = gradedCoordinates(0.0, width_m, cells, grading);
    std::vector<double> depth;
    for (double v : lateral) {
        depth.insert(depth.begin(), -v);
    }
    TissueMaterial material;
    material.youngs_modulus_pa = youngs;
    material.poisson_ratio = poisson;
    material.strain_limits = false;
    sim.addTissue(makeGridMesh(lateral, lateral, depth), material);
    // Symmetry planes x = 0 and y = 0 slide; the bottom is clamped.
    for (int i = 0; i < sim.nodeCount(); ++i) {
        const Vec3& p = sim.nodeRestPosition(i);
        sim.pinNode(i, {p.x() < 1e-12, p.y() < 1e-12, p.z() < -width_m + 1e-12});
    }
    const int sphere =
        sim.addCollider({Sphere{radius}, Vec3(0.0, 0.0, radius), Mat3::Identity(), 0.0});
    // Press in two increments so the contact set grows gradually.
    for (double fraction : {0.5, 1.0}) {
        sim.setColliderPose(sphere, Vec3(0.0, 0.0, radius - fraction * indentation_m),
                            Mat3::Identity());
        sim.relax(1.0, relaxSteps(60, profile), 1e-10);
    }
    const double force = 4.0 * sim.forceOnCollider(sphere).z();
    const double e_star = youngs / (1.0 - poisson * poisson);
    const double hertz = 4.0 / 3.0 * e_star * std::sqrt(radius) * std::pow(indentation_m, 1.5);
    return force / hertz;
}

}  // namespace haptic::softhand
