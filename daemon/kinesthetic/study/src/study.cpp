#include "haptic/kinesthetic/study.hpp"

#include <Eigen/LU>
#include <cmath>
#include <numbers>

namespace haptic::kinesthetic::study {

namespace {

RenderParameters parametersFor(const WallCase& wall, RenderingMethod method, RhoMode rho_mode,
                               double rho_override) {
    RenderParameters p;
    p.method = method;
    p.tracking_stiffness = wall.k_a;
    p.user_stiffness = wall.k_u;
    p.rho_mode = rho_mode;
    p.rho_override = rho_override;
    p.max_iterations = 32;
    return p;
}

// Large enough never to saturate in the study: saturation is the port guard's job.
constexpr double kStudyMaxForce = 1e6;

Eigen::VectorXd renderedForce(KinestheticRenderer& renderer, const Eigen::VectorXd& x,
                              const ConstraintMatrix& C, const ConstraintVector& d,
                              RenderOutput& out) {
    const ConfigVector q = x;
    const ConfigVector zero = ConfigVector::Zero(x.size());
    renderer.reset();
    renderer.tick(q, zero, C, d, out);
    return Eigen::VectorXd(out.rendered_force);
}

}  // namespace

void wallConstraint(int dim, ConstraintMatrix& C, ConstraintVector& d) {
    C = ConstraintMatrix::Zero(dim, 1);
    C(1, 0) = 1.0;
    d = ConstraintVector::Zero(1);
}

Eigen::MatrixXd actuatedDirection(double beta_rad) {
    Eigen::MatrixXd a(2, 1);
    a << std::sin(beta_rad), std::cos(beta_rad);
    return a;
}

EquilibriumResult solveEquilibrium(KinestheticRenderer& renderer, const Eigen::MatrixXd& K_u,
                                   const Eigen::VectorXd& x_u, const ConstraintMatrix& C,
                                   const ConstraintVector& d, int max_iterations) {
    const auto n = x_u.size();
    RenderOutput out;
    auto residual = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
        return K_u * (x_u - x) + renderedForce(renderer, x, C, d, out);
    };
    EquilibriumResult result;
    Eigen::VectorXd x = x_u;
    Eigen::VectorXd r = residual(x);
    const double force_scale = 1.0 + (K_u * x_u).norm();
    int iteration = 0;
    for (; iteration < max_iterations; ++iteration) {
        if (r.norm() <= 1e-13 * force_scale) {
            result.converged = true;
            break;
        }
        Eigen::MatrixXd jacobian(n, n);
        for (Eigen::Index i = 0; i < n; ++i) {
            const double h = 1e-7 * (1e-3 + std::abs(x[i]));
            Eigen::VectorXd xp = x;
            Eigen::VectorXd xm = x;
            xp[i] += h;
            xm[i] -= h;
            jacobian.col(i) = (residual(xp) - residual(xm)) / (2.0 * h);
        }
        const Eigen::VectorXd step = jacobian.partialPivLu().solve(-r);
        double t = 1.0;
        Eigen::VectorXd candidate = x + step;
        Eigen::VectorXd r_candidate = residual(candidate);
        while (r_candidate.norm() > r.norm() && t > 1e-6) {
            t *= 0.5;
            candidate = x + t * step;
            r_candidate = residual(candidate);
        }
        x = candidate;
        r = r_candidate;
    }
    result.iterations = iteration;
    result.x = x;
    result.rendered_force = renderedForce(renderer, x, C, d, out);
    result.proxy = out.proxy;
    result.rho = out.rho;
    result.residual = r.norm();
    return result;
}

WallMeasurement measureWall(const WallCase& wall, RenderingMethod method, RhoMode rho_mode,
                            double rho_override) {
    ConstraintMatrix C;
    ConstraintVector d;
    wallConstraint(2, C, d);
    const Eigen::MatrixXd K_u = wall.k_u * Eigen::MatrixXd::Identity(2, 2);
    const Eigen::Vector2d x_u(wall.intent_tangential_m, -wall.depth_u_m);

    const LinearPointDevice full_device(Eigen::MatrixXd::Identity(2, 2), kStudyMaxForce);
    KinestheticRenderer full(full_device,
                             parametersFor(wall, RenderingMethod::kStandard, RhoMode::kManual, 1));
    const EquilibriumResult reference = solveEquilibrium(full, K_u, x_u, C, d);

    const LinearPointDevice device(actuatedDirection(wall.beta_rad), kStudyMaxForce);
    KinestheticRenderer renderer(device, parametersFor(wall, method, rho_mode, rho_override));
    const EquilibriumResult eq = solveEquilibrium(renderer, K_u, x_u, C, d);

    const Eigen::Vector2d a = actuatedDirection(wall.beta_rad).col(0);
    const Eigen::Vector2d F_full = reference.rendered_force;
    const Eigen::Vector2d f_r = eq.rendered_force;
    const Eigen::Vector2d Pa_F_full = a * a.dot(F_full);
    WallMeasurement m;
    m.rho = eq.rho;
    m.full_force = F_full.norm();
    m.rendered_force = f_r.norm();
    m.normal_force = f_r.y();
    m.tangential_force = std::abs(f_r.x());
    m.ghost_force = (f_r - Pa_F_full).norm();
    m.force_error = (f_r - F_full).norm();
    m.converged = reference.converged && eq.converged;
    return m;
}

namespace {

// The point device and renderer a dynamic wall experiment (slide, pumping) runs.
struct WallRig {
    WallRig(const WallCase& wall, RenderingMethod method, RhoMode rho_mode, double rho_override)
        : device(actuatedDirection(wall.beta_rad), kStudyMaxForce),
          renderer(device, parametersFor(wall, method, rho_mode, rho_override)) {
        wallConstraint(2, C, d);
    }
    ConstraintMatrix C;
    ConstraintVector d;
    LinearPointDevice device;
    KinestheticRenderer renderer;
};

}  // namespace

SlideResult simulateSlide(const SlideCase& slide, RenderingMethod method, RhoMode rho_mode,
                          double rho_override) {
    const WallCase& wall = slide.wall;
    WallRig rig(wall, method, rho_mode, rho_override);
    KinestheticRenderer& renderer = rig.renderer;
    const Eigen::Vector2d a = actuatedDirection(wall.beta_rad).col(0);
    // Quasi-static fully actuated force (§6.4) as the target of the best match.
    const double full = wall.k_a * wall.k_u * wall.depth_u_m / (wall.k_u + wall.k_a);
    const Eigen::Vector2d Pa_F_full = a * a.dot(Eigen::Vector2d(0.0, full));

    const double T = slide.period_s;
    const int steps = static_cast<int>(std::lround(slide.duration_s / T));
    Eigen::Vector2d x(0.0, 0.0);
    Eigen::Vector2d v(0.0, 0.0);
    const Eigen::Vector2d intent_velocity(slide.slide_speed_m_per_s, 0.0);
    RenderOutput out;
    SlideResult result;
    double ghost_sq = 0.0;
    double drift_sq = 0.0;
    double normal_sum = 0.0;
    int samples = 0;
    for (int k = 0; k < steps; ++k) {
        const double t = k * T;
        const Eigen::Vector2d x_u(slide.slide_speed_m_per_s * t, -wall.depth_u_m);
        const ConfigVector q = x;
        const ConfigVector q_dot = v;
        renderer.tick(q, q_dot, rig.C, rig.d, out);
        const Eigen::Vector2d f_r = out.rendered_force;
        const Eigen::Vector2d f_user =
            wall.k_u * (x_u - x) + slide.user_damping_n_s_per_m * (intent_velocity - v);
        const Eigen::Vector2d accel =
            (f_user + f_r - slide.device_damping_n_s_per_m * v) / slide.device_mass_kg;
        v += T * accel;
        x += T * v;
        const double ghost = out.in_contact ? (f_r - Pa_F_full).norm() : 0.0;
        const double drift = x.x() - x_u.x();
        result.time_s.push_back(t);
        result.ghost_force.push_back(ghost);
        result.tangential_drift.push_back(drift);
        result.normal_force.push_back(f_r.y());
        if (k >= steps / 2) {
            ghost_sq += ghost * ghost;
            drift_sq += drift * drift;
            normal_sum += f_r.y();
            ++samples;
        }
    }
    if (samples > 0) {
        result.rms_ghost_force = std::sqrt(ghost_sq / samples);
        result.rms_tangential_drift = std::sqrt(drift_sq / samples);
        result.mean_normal_force = normal_sum / samples;
    }
    return result;
}

PumpingResult runEnergyPumping(const PumpingCase& pumping, RenderingMethod method, RhoMode rho_mode,
                               double rho_override, bool passivity_controller) {
    const WallCase& wall = pumping.wall;
    WallRig rig(wall, method, rho_mode, rho_override);
    KinestheticRenderer& renderer = rig.renderer;
    PortGuardConfig guard_config;
    guard_config.period_s = pumping.period_s;
    guard_config.max_force_n = 1e3;
    guard_config.max_force_rate_n_per_s = pumping.max_force_rate_n_per_s;
    guard_config.fade_time_s = pumping.period_s;  // full force from the first tick
    guard_config.passivity_enabled = passivity_controller;
    guard_config.passivity_port_mass_kg = pumping.device_mass_kg;
    ActuatorPortGuard guard(guard_config);

    const double T = pumping.period_s;
    const double omega = 2.0 * std::numbers::pi * pumping.loop_frequency_hz;
    const double direction = pumping.clockwise ? -1.0 : 1.0;
    // The user first pushes in from outside the wall, so the energy stored in the wall on the
    // way in is on the books before the loops start; then the intent circles inside the wall.
    const int approach_steps = static_cast<int>(std::lround(pumping.approach_s / T));
    const int loop_steps =
        static_cast<int>(std::lround(pumping.cycles / pumping.loop_frequency_hz / T));
    const Eigen::Vector2d centre(0.0, -wall.depth_u_m);
    const Eigen::Vector2d loop_start = centre + Eigen::Vector2d(pumping.loop_radius_m, 0.0);
    const Eigen::Vector2d outside(pumping.loop_radius_m, pumping.loop_radius_m);
    const Eigen::Vector2d a = actuatedDirection(wall.beta_rad).col(0);
    Eigen::Vector2d x = outside;
    Eigen::Vector2d v(0.0, 0.0);
    RenderOutput out;
    PumpingResult result;
    double generated = 0.0;
    for (int k = 0; k <= approach_steps + loop_steps; ++k) {
        Eigen::Vector2d x_u;
        Eigen::Vector2d v_u;
        if (k < approach_steps) {
            const double s = static_cast<double>(k) / approach_steps;
            x_u = outside + s * (loop_start - outside);
            v_u = (loop_start - outside) / pumping.approach_s;
        } else {
            const double phase = direction * omega * (k - approach_steps) * T;
            x_u =
                centre + pumping.loop_radius_m * Eigen::Vector2d(std::cos(phase), std::sin(phase));
            v_u = direction * omega * pumping.loop_radius_m *
                  Eigen::Vector2d(-std::sin(phase), std::cos(phase));
        }
        const ConfigVector q = x;
        const ConfigVector q_dot = v;
        renderer.tick(q, q_dot, rig.C, rig.d, out);
        const PortCommand command = guard.apply(out.actuator_force[0], a.dot(x), true);
        const Eigen::Vector2d f_device = a * command.force_n;
        result.max_force_n = std::max(result.max_force_n, std::abs(command.force_n));
        const Eigen::Vector2d f_user =
            wall.k_u * (x_u - x) + pumping.user_damping_n_s_per_m * (v_u - v);
        const Eigen::Vector2d accel =
            (f_user + f_device - pumping.device_damping_n_s_per_m * v) / pumping.device_mass_kg;
        v += T * accel;
        const Eigen::Vector2d x_next = x + T * v;
        // Measured here, not taken from the observer: the work of the force held over
        // [k, k+1] along the actuator coordinate, including the last tick.
        generated += command.force_n * (a.dot(x_next) - a.dot(x));
        x = x_next;
        result.time_s.push_back((k + 1) * T);
        result.generated_energy.push_back(generated);
    }
    result.generated_energy_j = generated;
    result.observer_energy_j = -guard.passivity().observedEnergy();
    return result;
}

}  // namespace haptic::kinesthetic::study
