#include "haptic/tactile/contact_optimiser.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <utility>

#include "haptic/tactile/pad_safety.hpp"

namespace haptic::tactile {

namespace {

// A constraint closer than this to its bound (dimensionless: rad, or lengths / plate radius)
// is reported as active.
constexpr double kActiveTolerance = 1e-3;
// The QP aims this far inside linearised bounds so that curved bounds stay feasible after a
// short backtrack.
constexpr double kQpMargin = 1e-4;
constexpr int kQpMaxIterations = 12;
constexpr int kLineSearchMaxHalvings = 12;
constexpr double kMaxStepM = 0.002;
// Gauss-Newton stops once the predicted decrease of E falls below this fraction of E.
constexpr double kNegligibleDecrease = 1e-6;
// Levenberg damping of the Gauss-Newton matrix (not part of E).
constexpr double kDamping = 1e-9;

using Matrix14x3 = Eigen::Matrix<double, kConstraintCount, 3>;

// Per-sample pad energy in units of weight x m^2, as a function of the signed distance d of the
// matched point to the plate (negative: plate past it). For the exponential pad law
// p(delta) = p0 (exp(delta / s) - 1) and stiffness weights w = A dp/d(delta) at the virtual
// indentation, A [U(delta_d) - p(delta_v) delta_d] (U' = p, delta_d = delta_v - d) equals, up
// to a constant, w s^2 (exp(-d / s) - 1 + d / s). Its gradient over the platform DoFs is the
// mismatch of the generalised pad forces; s -> infinity gives the quadratic w d^2 / 2.
struct PadEnergy {
    double value;  // psi(d)
    double slope;  // psi'(d)
    // psi''(d) = exp(-d / s), floored at 1 (the virtual contact stiffness the weight carries):
    // where the plate has left a point (d > 0) the energy is almost linear, and a Newton step
    // on that flat curvature would overshoot by orders of magnitude. The floor only changes
    // the step metric, not the stationary point.
    double curvature;
};

PadEnergy padEnergy(double d, double inverse_depth) noexcept {
    if (inverse_depth == 0.0) {
        return {0.5 * d * d, d, 1.0};
    }
    const double s = 1.0 / inverse_depth;
    const double x = -d * inverse_depth;
    const double growth_minus_one = std::expm1(x);
    return {s * s * (growth_minus_one - x), -s * growth_minus_one, 1.0 + growth_minus_one};
}

// min 1/2 D'HD + g'D  s.t.  c_j + G_j D >= margin, by a small active-set loop (at most three
// constraints active in three variables). Range-space form: with the working rows A,
// D = H^-1 (A' l - g) and (A H^-1 A') l = margin - c_A + A H^-1 g, at most 3x3 systems.
// Falls back to the last solvable working set.
Eigen::Vector3d solveStepQp(const Eigen::Matrix3d& H, const Eigen::Vector3d& g, const Matrix14x3& G,
                            const ConstraintValues& c) noexcept {
    // H is symmetric positive definite (damped); Eigen's closed-form 3x3 inverse avoids the
    // blocked triangular solver an LDLT with a matrix right-hand side goes through.
    const Eigen::Matrix3d H_inverse = H.inverse();
    const Eigen::Vector3d unconstrained = -H_inverse * g;
    std::array<int, 3> working{};
    int working_count = 0;
    Eigen::Vector3d step = unconstrained;
    Eigen::Vector3d multipliers = Eigen::Vector3d::Zero();
    for (int iteration = 0; iteration < kQpMaxIterations; ++iteration) {
        if (working_count > 0) {
            // Unused rows stay zero; the identity there keeps the 3x3 system regular.
            Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
            Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
            for (int k = 0; k < working_count; ++k) {
                const auto j = static_cast<std::size_t>(working[static_cast<std::size_t>(k)]);
                A.row(k) = G.row(static_cast<Eigen::Index>(j));
                rhs(k) = kQpMargin - c[j] - A.row(k).dot(unconstrained);
            }
            Eigen::Matrix3d schur = A * H_inverse * A.transpose();
            const double scale = schur.diagonal().head(working_count).maxCoeff();
            for (int k = working_count; k < 3; ++k) {
                schur(k, k) = scale > 0.0 ? scale : 1.0;
            }
            const Eigen::LDLT<Eigen::Matrix3d> ldlt(schur);
            const double smallest = ldlt.vectorD().cwiseAbs().minCoeff();
            if (ldlt.info() != Eigen::Success || !(scale > 0.0) || smallest <= 1e-12 * scale) {
                --working_count;  // dependent bounds: keep the previous solution
                break;
            }
            multipliers = ldlt.solve(rhs);
            step = unconstrained + H_inverse * (A.transpose() * multipliers);
        }

        int most_violated = -1;
        double worst = -1e-12;
        for (int j = 0; j < kConstraintCount; ++j) {
            const bool in_working = std::find(working.begin(), working.begin() + working_count,
                                              j) != working.begin() + working_count;
            const double value = c[static_cast<std::size_t>(j)] + G.row(j).dot(step) - kQpMargin;
            if (!in_working && value < worst) {
                worst = value;
                most_violated = j;
            }
        }
        if (most_violated >= 0 && working_count < 3) {
            working[static_cast<std::size_t>(working_count++)] = most_violated;
            continue;
        }
        int most_negative = -1;
        double lowest = 0.0;
        for (int k = 0; k < working_count; ++k) {
            if (multipliers(k) < lowest) {
                lowest = multipliers(k);
                most_negative = k;
            }
        }
        if (most_negative < 0) {
            break;
        }
        working[static_cast<std::size_t>(most_negative)] =
            working[static_cast<std::size_t>(--working_count)];
        multipliers(most_negative) = multipliers(working_count);
        multipliers(working_count) = 0.0;
        if (working_count == 0) {
            step = unconstrained;
        }
    }
    return step;
}

}  // namespace

OptimiserSettings OptimiserSettings::fromConfig(const config::ThimbleConfig& config) {
    OptimiserSettings settings;
    settings.max_iterations = config.optimiser.max_iterations;
    settings.max_samples = config.optimiser.pad_samples;
    settings.pad_stiffening_depth_m = config.optimiser.pad_stiffening_depth_m;
    return settings;
}

const char* toString(InputError error) noexcept {
    switch (error) {
        case InputError::kNone:
            return "ok";
        case InputError::kTooManySamples:
            return "more samples than optimiser.pad_samples";
        case InputError::kNonFinitePosition:
            return "sample position is NaN or infinite";
        case InputError::kNonFiniteDistance:
            return "sample signed distance is NaN or infinite";
        case InputError::kNonFiniteNormal:
            return "sample normal is NaN or infinite";
        case InputError::kNonFiniteWeight:
            return "sample weight is NaN or infinite";
        case InputError::kNegativeWeight:
            return "sample weight is negative";
        case InputError::kNormalNotUnit:
            return "contact sample normal is not unit length";
        case InputError::kOutOfFrame:
            return "sample outside the device frame bounds";
    }
    return "unknown";
}

const char* toString(SolveOutcome outcome) noexcept {
    switch (outcome) {
        case SolveOutcome::kMatched:
            return "matched";
        case SolveOutcome::kRetractedNoContact:
            return "retracted (no contact)";
        case SolveOutcome::kRejectedInput:
            return "retracted (input rejected)";
    }
    return "unknown";
}

InputCheck checkContactSurface(const msgs::ContactSurface& surface,
                               const OptimiserSettings& settings) noexcept {
    if (surface.samples.count > static_cast<std::uint32_t>(settings.max_samples)) {
        return {InputError::kTooManySamples, static_cast<int>(surface.samples.count)};
    }
    auto allFinite = [](const std::array<double, 3>& v) {
        return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
    };
    for (std::uint32_t i = 0; i < surface.samples.count; ++i) {
        const msgs::ContactSample& s = surface.samples[i];
        const int index = static_cast<int>(i);
        if (!allFinite(s.p_device_m)) {
            return {InputError::kNonFinitePosition, index};
        }
        if (!std::isfinite(s.signed_distance_m)) {
            return {InputError::kNonFiniteDistance, index};
        }
        if (!allFinite(s.normal_device)) {
            return {InputError::kNonFiniteNormal, index};
        }
        if (!std::isfinite(s.weight)) {
            return {InputError::kNonFiniteWeight, index};
        }
        if (s.weight < 0.0) {
            return {InputError::kNegativeWeight, index};
        }
        const Eigen::Vector3d p(s.p_device_m[0], s.p_device_m[1], s.p_device_m[2]);
        if (p.norm() > settings.frame_limit_m ||
            std::fabs(s.signed_distance_m) > settings.frame_limit_m) {
            return {InputError::kOutOfFrame, index};
        }
        const Eigen::Vector3d n(s.normal_device[0], s.normal_device[1], s.normal_device[2]);
        if (s.signed_distance_m < 0.0 && std::fabs(n.norm() - 1.0) > settings.normal_tolerance) {
            return {InputError::kNormalNotUnit, index};
        }
    }
    return {};
}

ContactSurfaceOptimiser::ContactSurfaceOptimiser(const ThimbleKinematics& kinematics,
                                                 const OptimiserSettings& settings)
    : kinematics_(kinematics), settings_(settings), warm_start_(kinematics.retractPose()) {
    settings_.max_samples =
        std::clamp(settings_.max_samples, 0, static_cast<int>(msgs::kMaxContactSamples));
    settings_.max_iterations = std::max(settings_.max_iterations, 1);
    inverse_stiffening_depth_ =
        std::isfinite(settings_.pad_stiffening_depth_m) && settings_.pad_stiffening_depth_m > 0.0
            ? 1.0 / settings_.pad_stiffening_depth_m
            : 0.0;
}

Eigen::Vector3d ContactSurfaceOptimiser::scaled(const PlatformDofs& dofs) const noexcept {
    const double r = kinematics_.config().plate_radius_m;
    return {dofs.height_m, r * dofs.tilt_x_rad, r * dofs.tilt_y_rad};
}

PlatformDofs ContactSurfaceOptimiser::unscaled(const Eigen::Vector3d& z) const noexcept {
    const double r = kinematics_.config().plate_radius_m;
    return {z.x(), z.y() / r, z.z() / r};
}

double ContactSurfaceOptimiser::rimWeight(double in_plane_radius_sq_m2) const noexcept {
    return plateRimWeight(in_plane_radius_sq_m2, kinematics_.config().plate_radius_m,
                          settings_.rim_blend_m);
}

ContactSurfaceOptimiser::Evaluation ContactSurfaceOptimiser::evaluate(
    const PlatformDofs& dofs, const PlatformPose& pose, SampleStates& states) const noexcept {
    Evaluation e;
    const Eigen::Vector3d normal = pose.plateNormal();
    for (int i = 0; i < target_count_; ++i) {
        const Target& t = targets_[static_cast<std::size_t>(i)];
        const Eigen::Vector3d rel = t.point_m - pose.position_m;
        const double d = normal.dot(rel);
        const double weight = rimWeight(rel.squaredNorm() - d * d);
        const double w = t.sqrt_weight * t.sqrt_weight * weight * weight;
        SampleState& state = states[static_cast<std::size_t>(i)];
        state.d = d;
        state.weight = 0.0;
        if (weight == 0.0 || (!t.contact && d >= 0.0)) {
            continue;
        }
        const PadEnergy energy = padEnergy(d, inverse_stiffening_depth_);
        state.weight = t.sqrt_weight * weight;
        state.slope = energy.slope;
        state.curvature = energy.curvature;
        e.objective += 2.0 * w * energy.value;
        if (t.contact) {
            e.contact_sq_sum += w * d * d;
            e.contact_weight += w;
        } else {
            e.overlap_m = std::max(e.overlap_m, -d);
        }
    }
    const Eigen::Vector3d smooth = scaled(dofs) - scaled(warm_start_);
    e.objective += lambda_ * smooth.squaredNorm();
    return e;
}

TactileCommand ContactSurfaceOptimiser::solve(const msgs::ContactSurface& surface) noexcept {
    SolveReport report;
    report.input = checkContactSurface(surface, settings_);
    if (!report.input.ok()) {
        report.outcome = SolveOutcome::kRejectedInput;
        return finish(kinematics_.retractPose(), report);
    }

    double total_weight = 0.0;
    double contact_weight = 0.0;
    for (const msgs::ContactSample& s : surface.samples) {
        total_weight += s.weight;
        contact_weight += s.signed_distance_m < 0.0 ? s.weight : 0.0;
    }
    if (!(contact_weight > 0.0)) {
        report.outcome = SolveOutcome::kRetractedNoContact;
        report.converged = true;
        return finish(kinematics_.retractPose(), report);
    }
    target_count_ = 0;
    Eigen::Vector3d contact_centroid = Eigen::Vector3d::Zero();
    Eigen::Vector3d contact_normal = Eigen::Vector3d::Zero();
    for (const msgs::ContactSample& s : surface.samples) {
        Target& t = targets_[static_cast<std::size_t>(target_count_++)];
        const Eigen::Vector3d p(s.p_device_m[0], s.p_device_m[1], s.p_device_m[2]);
        const Eigen::Vector3d n(s.normal_device[0], s.normal_device[1], s.normal_device[2]);
        t.contact = s.signed_distance_m < 0.0;
        t.point_m = t.contact ? Eigen::Vector3d(p - s.signed_distance_m * n) : p;
        const double eta = t.contact ? 1.0 : settings_.non_contact_weight;
        t.sqrt_weight = std::sqrt(eta * s.weight / total_weight);
        if (t.contact) {
            contact_centroid += s.weight * t.point_m;
            contact_normal += s.weight * n;
        }
    }
    report.outcome = SolveOutcome::kMatched;

    // A new contact starts from the plane through the contact centroid with the average
    // normal (the geometric baseline). When that plane is not reachable (usually too much
    // tilt), the largest reachable fraction of its tilt at the same height: a start on the
    // right side of the pad, strictly inside the workspace (a start projected onto a bound
    // stalls the backtracking). The retract pose is the last resort.
    PlatformDofs dofs = kinematics_.projectToWorkspace(warm_start_);
    ConstraintValues values{};
    PlatformPose pose;
    if (!previous_matched_ && contact_normal.norm() > 1e-12) {
        const PlatformDofs plane =
            poseForPlane(kinematics_, contact_normal, contact_centroid / contact_weight);
        for (const double tilt_fraction : {1.0, 0.8, 0.6, 0.4, 0.2, 0.0}) {
            const PlatformDofs start{plane.height_m, tilt_fraction * plane.tilt_x_rad,
                                     tilt_fraction * plane.tilt_y_rad};
            if (kinematics_.constraints(start, values) && ThimbleKinematics::feasible(values)) {
                dofs = start;
                break;
            }
        }
    }
    if (!kinematics_.constraints(dofs, values, &pose) || !ThimbleKinematics::feasible(values)) {
        dofs = kinematics_.retractPose();
        (void)kinematics_.constraints(dofs, values, &pose);
    }
    // Per-sample state at the current pose (the Gauss-Newton loop reuses it) and at the
    // line-search candidate; swapped on acceptance.
    SampleStates* current_states = &sample_states_[0];
    SampleStates* candidate_states = &sample_states_[1];
    Evaluation current = evaluate(dofs, pose, *current_states);
    lambda_ = previous_matched_ ? settings_.smoothness_weight : 0.0;

    const double plate_radius = kinematics_.config().plate_radius_m;
    for (report.iterations = 0; report.iterations < settings_.max_iterations;) {
        ++report.iterations;
        const Eigen::Vector3d z = scaled(dofs);
        // Analytic Jacobians over xi, then to the scaled z = (h, r tilt_x, r tilt_y).
        Matrix14x3 G;
        PoseJacobian pose_rate;
        if (!kinematics_.constraintJacobian(dofs, pose, G, pose_rate)) {
            break;  // cannot happen on a feasible pose; not converged then
        }
        const Eigen::DiagonalMatrix<double, 3> to_scaled(1.0, 1.0 / plate_radius,
                                                         1.0 / plate_radius);
        G = G * to_scaled;

        // Gauss-Newton normal equations, accumulated per sample (no residual storage).
        // kDamping keeps H definite with fewer than three independent contact points.
        Eigen::Matrix3d H = (lambda_ + kDamping) * Eigen::Matrix3d::Identity();
        Eigen::Vector3d g = lambda_ * (z - scaled(warm_start_));
        const Eigen::Vector3d normal = pose.plateNormal();
        // d(x) = n . (x - p), so d d / d z_k = dn_k . x - (dn_k . p + n . dp_k): two numbers per
        // direction serve every sample.
        const Eigen::Matrix3d normal_change = (pose_rate.normal * to_scaled).transpose();
        const Eigen::Vector3d offset_change =
            normal_change * pose.position_m +
            (pose_rate.position_m * to_scaled).transpose() * normal;
        for (int i = 0; i < target_count_; ++i) {
            const SampleState& state = (*current_states)[static_cast<std::size_t>(i)];
            if (state.weight == 0.0) {
                continue;
            }
            const Eigen::Vector3d row =
                state.weight *
                (normal_change * targets_[static_cast<std::size_t>(i)].point_m - offset_change);
            H.noalias() += state.curvature * (row * row.transpose());
            g += row * (state.weight * state.slope);
        }

        Eigen::Vector3d step = solveStepQp(H, g, G, values);
        // Trust region: where the plate has left the points (d > 0) the pad energy is almost
        // linear and the Newton step would overshoot by orders of magnitude.
        if (step.norm() > kMaxStepM) {
            step *= kMaxStepM / step.norm();
        }
        if (step.norm() < settings_.step_tolerance_m) {
            report.converged = true;  // within tolerance of the stationary point already
            break;
        }
        const double slope = g.dot(step);
        const double predicted = -(slope + 0.5 * step.dot(H * step));
        if (predicted <= kNegligibleDecrease * current.objective) {
            // The model cannot lower E by more than a negligible fraction any more; on a
            // pose held against a workspace bound this saves the last one or two iterations.
            report.converged = true;
            break;
        }
        bool accepted = false;
        double alpha = 1.0;
        for (int halving = 0; halving < kLineSearchMaxHalvings; ++halving, alpha *= 0.5) {
            const PlatformDofs candidate = unscaled(z + alpha * step);
            ConstraintValues candidate_values{};
            PlatformPose candidate_pose;
            if (!kinematics_.constraints(candidate, candidate_values, &candidate_pose, &pose) ||
                !ThimbleKinematics::feasible(candidate_values)) {
                continue;
            }
            const Evaluation e = evaluate(candidate, candidate_pose, *candidate_states);
            if (e.objective <= current.objective + 1e-4 * alpha * std::min(slope, 0.0)) {
                dofs = candidate;
                values = candidate_values;
                pose = candidate_pose;
                current = e;
                std::swap(current_states, candidate_states);
                accepted = true;
                break;
            }
        }
        if (!accepted) {
            // Nothing feasible lowers E along this step: stationary up to the model's accuracy.
            report.converged = predicted <= 1e-12 * (1.0 + current.objective) ||
                               step.norm() < settings_.step_tolerance_m;
            break;
        }
        if (alpha * step.norm() < settings_.step_tolerance_m) {
            report.converged = true;
            break;
        }
    }

    report.objective = current.objective;
    report.contact_rms_m = current.contact_weight > 0.0
                               ? std::sqrt(current.contact_sq_sum / current.contact_weight)
                               : 0.0;
    report.non_contact_overlap_m = current.overlap_m;
    for (int j = 0; j < kConstraintCount; ++j) {
        if (values[static_cast<std::size_t>(j)] < kActiveTolerance) {
            report.active_constraints |= 1U << j;
        }
    }
    report.clamped = report.active_constraints != 0;
    report.poor_match = report.contact_rms_m > settings_.match_tolerance_m;
    return finish(dofs, report);
}

TactileCommand ContactSurfaceOptimiser::finish(const PlatformDofs& dofs,
                                               SolveReport report) noexcept {
    TactileCommand command;
    const InverseResult ik = kinematics_.inverse(dofs);
    // Every path above ends on a feasible pose; the retract pose is the fallback if the
    // geometry ever says otherwise.
    const InverseResult& safe = ik.ok() ? ik : kinematics_.inverse(kinematics_.retractPose());
    command.dofs = ik.ok() ? dofs : kinematics_.retractPose();
    command.servo_rad = safe.servo_rad;
    command.pose = safe.pose;
    command.report = report;
    warm_start_ = command.dofs;
    previous_matched_ = report.outcome == SolveOutcome::kMatched && ik.ok();
    return command;
}

}  // namespace haptic::tactile
