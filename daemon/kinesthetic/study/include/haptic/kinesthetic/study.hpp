#pragma once

// The synthetic chapter 6 study (docs/algorithms.md §6.10) as plain functions, so the study tool
// and the tests run the same code. Not for the 1 kHz loop (these allocate and iterate freely).
//
// Setup: 2-D point device with one actuated direction a = (sin beta, cos beta), wall y >= 0
// (n = (0, 1)), user = spring K_u (plus damping in the dynamic runs) pulling the device to an
// intent x_u inside the wall. Every force comes from the real renderer (KinestheticRenderer)
// ticking on the device state; the closed forms of §6.6 are only used to compare.

#include <vector>

#include "haptic/kinesthetic/port_safety.hpp"
#include "haptic/kinesthetic/renderer.hpp"

namespace haptic::kinesthetic::study {

struct EquilibriumResult {
    ConfigVector x;               // device position at equilibrium
    ConfigVector rendered_force;  // B u at x
    ConfigVector proxy;
    double rho{1.0};
    double residual{0.0};  // |K_u (x_u - x) + f_r(x)|
    int iterations{0};
    bool converged{false};
};

// Quasi-static equilibrium K_u (x_u - x) + f_r(x) = 0 by Newton's method with a finite-
// difference Jacobian of the renderer (f_r is piecewise linear, so Newton lands exactly once the
// contact set is right) and step halving.
[[nodiscard]] EquilibriumResult solveEquilibrium(
    KinestheticRenderer& renderer, const Eigen::MatrixXd& K_u, const Eigen::VectorXd& x_u,
    const ConstraintMatrix& C, const ConstraintVector& d, int max_iterations = 60);

// The §6.10 wall: n = (0, 1) through the origin.
void wallConstraint(int dim, ConstraintMatrix& C, ConstraintVector& d);
// a = (sin beta, cos beta): beta is the angle between the actuated direction and the normal.
[[nodiscard]] Eigen::MatrixXd actuatedDirection(double beta_rad);

struct WallCase {
    double beta_rad{0.0};
    double k_a{1000.0};
    double k_u{300.0};
    double depth_u_m{0.01};
    double intent_tangential_m{0.3};
};

struct WallMeasurement {
    double rho{1.0};
    double full_force{0.0};  // |F_full| from the fully actuated equilibrium
    double rendered_force{0.0};
    double normal_force{0.0};
    double tangential_force{0.0};
    double ghost_force{0.0};  // |f_r - P_a F_full|
    double force_error{0.0};  // |f_r - F_full|
    bool converged{false};
};

// Both equilibria (fully actuated reference with `standard`, and the underactuated device with
// `method`/`rho`) solved numerically through the renderer.
[[nodiscard]] WallMeasurement measureWall(const WallCase& wall, RenderingMethod method,
                                          RhoMode rho_mode, double rho_override);

struct SlideCase {
    WallCase wall;
    double device_mass_kg{0.1};
    double device_damping_n_s_per_m{2.0};
    double user_damping_n_s_per_m{5.0};
    double slide_speed_m_per_s{0.05};
    double duration_s{2.0};
    double period_s{1e-3};
};

struct SlideResult {
    double rms_ghost_force{0.0};       // over the second half (steady sliding)
    double rms_tangential_drift{0.0};  // x_t - x_{u,t}
    double mean_normal_force{0.0};
    std::vector<double> time_s, ghost_force, tangential_drift, normal_force;
};

// Dynamic user model: intent slides along the wall at constant depth; device mass and damping;
// semi-implicit Euler at 1 kHz.
[[nodiscard]] SlideResult simulateSlide(const SlideCase& slide, RenderingMethod method,
                                        RhoMode rho_mode, double rho_override);

struct PumpingCase {
    WallCase wall;  // beta, stiffnesses; depth_u is the loop centre depth
    double loop_radius_m{0.004};
    double loop_frequency_hz{2.0};
    int cycles{5};
    double approach_s{0.5};  // pushing in from outside the wall before the loops
    bool clockwise{false};
    double device_mass_kg{0.1};
    double device_damping_n_s_per_m{1.0};
    double user_damping_n_s_per_m{5.0};
    double max_force_rate_n_per_s{500.0};  // as config/devices/exoskeleton.yaml
    double period_s{1e-3};
};

struct PumpingResult {
    // Work done by the actuator on the user, sum of u_k (ell_{k+1} - ell_k), measured by the
    // simulation itself; > 0 means the device generated energy.
    double generated_energy_j{0.0};
    // The passivity observer's own book, -E: the same sum without the last tick.
    double observer_energy_j{0.0};
    double max_force_n{0.0};
    std::vector<double> time_s, generated_energy;  // running total
};

// Closed loops inside the wall with the intent circling; the actuator port goes through an
// ActuatorPortGuard with the passivity controller on or off.
[[nodiscard]] PumpingResult runEnergyPumping(const PumpingCase& pumping, RenderingMethod method,
                                             RhoMode rho_mode, double rho_override,
                                             bool passivity_controller);

}  // namespace haptic::kinesthetic::study
