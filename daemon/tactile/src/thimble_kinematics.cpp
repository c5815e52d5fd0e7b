#include "haptic/tactile/thimble_kinematics.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace haptic::tactile {

namespace {

const Eigen::Vector3d kZ = Eigen::Vector3d::UnitZ();

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
    Eigen::Matrix3d m;
    m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
    return m;
}

Eigen::Matrix3d yawRotation(double yaw) {
    const double c = std::cos(yaw);
    const double s = std::sin(yaw);
    Eigen::Matrix3d m;
    m << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
    return m;
}

bool finite(const PlatformDofs& dofs) {
    return std::isfinite(dofs.height_m) && std::isfinite(dofs.tilt_x_rad) &&
           std::isfinite(dofs.tilt_y_rad);
}

constexpr int kParasiticMaxIterations = 20;
constexpr int kForwardMaxIterations = 40;
constexpr double kForwardToleranceRad = 1e-13;

}  // namespace

Eigen::Matrix3d tiltRotation(double tilt_x_rad, double tilt_y_rad) noexcept {
    const Eigen::Vector3d k(tilt_x_rad, tilt_y_rad, 0.0);
    const double t2 = k.squaredNorm();
    const double t = std::sqrt(t2);
    // Rodrigues with sin(t)/t and (1 - cos t)/t^2 written as series near zero, so finite
    // differences through the untilted pose stay smooth.
    const double a = t < 1e-4 ? 1.0 - t2 / 6.0 : std::sin(t) / t;
    const double b = t < 1e-4 ? 0.5 - t2 / 24.0 : (1.0 - std::cos(t)) / t2;
    const Eigen::Matrix3d K = skew(k);
    return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

namespace {

// d tiltRotation / d tilt_x and d tilt_y, differentiating R = I + a K + b K^2 with
// a = sin t / t, b = (1 - cos t) / t^2, K = [k]x, k = (tilt_x, tilt_y, 0).
std::array<Eigen::Matrix3d, 2> tiltRotationRates(double tilt_x_rad, double tilt_y_rad) noexcept {
    const Eigen::Vector3d k(tilt_x_rad, tilt_y_rad, 0.0);
    const double t2 = k.squaredNorm();
    const double t = std::sqrt(t2);
    double a = 0.0;
    double b = 0.0;
    double a_rate_over_t = 0.0;  // (da/dt) / t
    double b_rate_over_t = 0.0;  // (db/dt) / t
    if (t < 1e-4) {
        a = 1.0 - t2 / 6.0;
        b = 0.5 - t2 / 24.0;
        a_rate_over_t = -1.0 / 3.0 + t2 / 30.0;
        b_rate_over_t = -1.0 / 12.0 + t2 / 180.0;
    } else {
        const double sine = std::sin(t);
        const double cosine = std::cos(t);
        a = sine / t;
        b = (1.0 - cosine) / t2;
        a_rate_over_t = (t * cosine - sine) / (t2 * t);
        b_rate_over_t = (t * sine - 2.0 * (1.0 - cosine)) / (t2 * t2);
    }
    const Eigen::Matrix3d K = skew(k);
    const Eigen::Matrix3d K2 = K * K;
    std::array<Eigen::Matrix3d, 2> rates;
    for (int axis = 0; axis < 2; ++axis) {
        const double component = k(axis);
        const Eigen::Matrix3d dK = skew(Eigen::Vector3d::Unit(axis));
        rates[static_cast<std::size_t>(axis)] = component * a_rate_over_t * K + a * dK +
                                                component * b_rate_over_t * K2 +
                                                b * (dK * K + K * dK);
    }
    return rates;
}

}  // namespace

std::array<double, 2> tiltForNormal(const Eigen::Vector3d& normal) noexcept {
    const Eigen::Vector3d m = -normal.normalized();   // R_tilt z
    const Eigen::Vector3d axis_scaled = kZ.cross(m);  // (-m_y, m_x, 0)
    const double s = axis_scaled.norm();
    const double angle = std::atan2(s, m.z());
    if (s < 1e-15) {
        return {0.0, 0.0};
    }
    return {angle * axis_scaled.x() / s, angle * axis_scaled.y() / s};
}

const char* toString(KinematicsError error) noexcept {
    switch (error) {
        case KinematicsError::kNone:
            return "ok";
        case KinematicsError::kNonFinite:
            return "non-finite platform DoFs";
        case KinematicsError::kParasiticNotConverged:
            return "parasitic-motion solve did not converge";
        case KinematicsError::kLegUnreachable:
            return "leg cannot close (distance outside crank/link range)";
        case KinematicsError::kTiltLimit:
            return "tilt above max_tilt_deg";
        case KinematicsError::kIndentationLimit:
            return "plate past contact_height - max_indentation";
        case KinematicsError::kServoBelowMin:
            return "servo angle below servos.min_deg";
        case KinematicsError::kServoAboveMax:
            return "servo angle above servos.max_deg";
        case KinematicsError::kReachMargin:
            return "leg within the singularity margin";
        case KinematicsError::kJointCone:
            return "spherical joint beyond its cone";
        case KinematicsError::kForwardNotConverged:
            return "forward kinematics did not converge";
    }
    return "unknown";
}

const char* constraintName(int index) noexcept {
    static constexpr std::array<const char*, kConstraintCount> kNames{
        "tilt",       "indentation", "servo0_min", "servo1_min", "servo2_min",
        "servo0_max", "servo1_max",  "servo2_max", "reach0",     "reach1",
        "reach2",     "cone0",       "cone1",      "cone2"};
    return index >= 0 && index < kConstraintCount ? kNames[static_cast<std::size_t>(index)]
                                                  : "unknown";
}

ThimbleKinematics::ThimbleKinematics(const config::ThimbleConfig& config) : config_(config) {
    const auto& g = config_.geometry;
    for (std::size_t i = 0; i < 3; ++i) {
        const double gamma = g.leg_angles_rad[i];
        radial_[i] = Eigen::Vector3d(std::cos(gamma), std::sin(gamma), 0.0);
        servo_axis_[i] = kZ.cross(radial_[i]);
        base_joint_[i] = g.base_radius_m * radial_[i];
        platform_arm_[i] = g.platform_radius_m * radial_[i];
    }
    const auto& calib = config_.finger_calibration;
    min_height_m_ = calib.contact_height_m - calib.max_indentation_m;
    computeWorkspace();
}

KinematicsError ThimbleKinematics::platformPose(const PlatformDofs& dofs, PlatformPose& pose,
                                                const PlatformPose* guess) const noexcept {
    if (!finite(dofs)) {
        return KinematicsError::kNonFinite;
    }
    const Eigen::Matrix3d tilt = tiltRotation(dofs.tilt_x_rad, dofs.tilt_y_rad);
    // Unknowns (p_x, p_y, yaw): each spherical joint must stay in its leg plane,
    // a_i . (p + R s_i) = 0 (a_i . B_i = 0 by construction).
    Eigen::Vector3d unknowns = Eigen::Vector3d::Zero();
    if (guess != nullptr && guess->position_m.allFinite() && std::isfinite(guess->yaw_rad)) {
        unknowns = Eigen::Vector3d(guess->position_m.x(), guess->position_m.y(), guess->yaw_rad);
    }
    const double scale = config_.geometry.platform_radius_m;
    for (int iteration = 0; iteration < kParasiticMaxIterations; ++iteration) {
        const Eigen::Matrix3d rotation = tilt * yawRotation(unknowns.z());
        const Eigen::Vector3d p(unknowns.x(), unknowns.y(), dofs.height_m);
        Eigen::Vector3d residual;
        Eigen::Matrix3d jacobian;
        for (int i = 0; i < 3; ++i) {
            const auto leg = static_cast<std::size_t>(i);
            const Eigen::Vector3d& a = servo_axis_[leg];
            residual(i) = a.dot(p + rotation * platform_arm_[leg]);
            jacobian(i, 0) = a.x();
            jacobian(i, 1) = a.y();
            jacobian(i, 2) = a.dot(rotation * kZ.cross(platform_arm_[leg]));
        }
        if (residual.cwiseAbs().maxCoeff() < 1e-12 * scale) {
            pose.position_m = p;
            pose.rotation = rotation;
            pose.yaw_rad = unknowns.z();
            return KinematicsError::kNone;
        }
        // Closed-form 3x3 inverse: a third of the cost of an LU here, and a singular
        // Jacobian (never inside the workspace) shows as non-finite unknowns below.
        unknowns -= jacobian.inverse() * residual;
        if (!unknowns.allFinite() || std::fabs(unknowns.z()) > 1.0) {
            return KinematicsError::kParasiticNotConverged;
        }
    }
    return KinematicsError::kParasiticNotConverged;
}

bool ThimbleKinematics::solveLeg(int leg, const PlatformPose& pose,
                                 LegSolution& out) const noexcept {
    const auto i = static_cast<std::size_t>(leg);
    const auto& g = config_.geometry;
    out.joint_m = pose.position_m + pose.rotation * platform_arm_[i];
    const Eigen::Vector3d rel = out.joint_m - base_joint_[i];
    const double u = radial_[i].dot(rel);
    const double w = rel.z();
    // Lengths of centimetres cannot overflow; std::hypot's care costs 5 % of a solve.
    const double rho = std::sqrt(u * u + w * w);
    const double kappa =
        (u * u + w * w + g.crank_length_m * g.crank_length_m - g.link_length_m * g.link_length_m) /
        (2.0 * g.crank_length_m);
    if (!(rho > 0.0)) {
        return false;
    }
    out.reach_ratio = std::fabs(kappa) / rho;
    if (out.reach_ratio > 1.0) {
        return false;
    }
    // Assembly branch of the device: elbow outward of the line B_i -> S_i.
    out.servo_rad = std::atan2(w, u) - std::acos(kappa / rho);
    out.elbow_m = base_joint_[i] + g.crank_length_m * (std::cos(out.servo_rad) * radial_[i] +
                                                       std::sin(out.servo_rad) * kZ);
    return true;
}

bool ThimbleKinematics::solveLegs(const PlatformPose& pose, LegSolutions& out,
                                  int* unreachable_leg) const noexcept {
    for (int leg = 0; leg < 3; ++leg) {
        if (!solveLeg(leg, pose, out[static_cast<std::size_t>(leg)])) {
            if (unreachable_leg != nullptr) {
                *unreachable_leg = leg;
            }
            return false;
        }
    }
    return true;
}

bool ThimbleKinematics::rawServoAngles(const PlatformDofs& dofs, ServoAngles& out) const noexcept {
    PlatformPose pose;
    if (platformPose(dofs, pose) != KinematicsError::kNone) {
        return false;
    }
    LegSolutions legs;
    if (!solveLegs(pose, legs)) {
        return false;
    }
    for (std::size_t i = 0; i < 3; ++i) {
        out[i] = legs[i].servo_rad;
    }
    return true;
}

bool ThimbleKinematics::constraints(const PlatformDofs& dofs, ConstraintValues& values,
                                    PlatformPose* pose_out,
                                    const PlatformPose* guess) const noexcept {
    PlatformPose pose;
    if (platformPose(dofs, pose, guess) != KinematicsError::kNone) {
        return false;
    }
    const double length_scale = config_.plate_radius_m;
    values[0] = config_.max_tilt_rad -
                std::sqrt(dofs.tilt_x_rad * dofs.tilt_x_rad + dofs.tilt_y_rad * dofs.tilt_y_rad);
    values[1] = (dofs.height_m - min_height_m_) / length_scale;
    const double reach_limit = std::cos(kElbowMarginRad);
    const Eigen::Vector3d towards_body = pose.plateNormal();
    LegSolutions legs;
    if (!solveLegs(pose, legs)) {
        return false;
    }
    for (std::size_t i = 0; i < 3; ++i) {
        const LegSolution& s = legs[i];
        values[2 + i] = s.servo_rad - config_.servos.min_rad;
        values[5 + i] = config_.servos.max_rad - s.servo_rad;
        values[8 + i] = reach_limit - s.reach_ratio;
        const Eigen::Vector3d link = (s.elbow_m - s.joint_m).normalized();
        const double cone = std::acos(std::clamp(link.dot(towards_body), -1.0, 1.0));
        values[11 + i] = config_.spherical_joint_max_rad - cone;
    }
    if (pose_out != nullptr) {
        *pose_out = pose;
    }
    return true;
}

bool ThimbleKinematics::constraintJacobian(const PlatformDofs& dofs, const PlatformPose& pose,
                                           ConstraintJacobian& jacobian,
                                           PoseJacobian& pose_jacobian) const noexcept {
    const double tx = dofs.tilt_x_rad;
    const double ty = dofs.tilt_y_rad;
    const Eigen::Matrix3d yaw = yawRotation(pose.yaw_rad);
    const auto tilt_rates = tiltRotationRates(tx, ty);
    const std::array<Eigen::Matrix3d, 3> tilt_rate{Eigen::Matrix3d::Zero(), tilt_rates[0] * yaw,
                                                   tilt_rates[1] * yaw};
    // Parasitic motion u = (p_x, p_y, yaw) from a_i . (p + R s_i) = 0: J_u du = -dr/dxi.
    Eigen::Matrix3d j_u;
    Eigen::Matrix3d r_xi;
    for (int i = 0; i < 3; ++i) {
        const auto leg = static_cast<std::size_t>(i);
        const Eigen::Vector3d& a = servo_axis_[leg];
        j_u(i, 0) = a.x();
        j_u(i, 1) = a.y();
        j_u(i, 2) = a.dot(pose.rotation * kZ.cross(platform_arm_[leg]));
        r_xi(i, 0) = a.z();
        r_xi(i, 1) = a.dot(tilt_rate[1] * platform_arm_[leg]);
        r_xi(i, 2) = a.dot(tilt_rate[2] * platform_arm_[leg]);
    }
    const Eigen::Matrix3d u_xi = -j_u.inverse() * r_xi;  // closed form, as in platformPose
    if (!u_xi.allFinite()) {
        return false;
    }
    std::array<Eigen::Matrix3d, 3> rotation_rate;
    const Eigen::Matrix3d yaw_rate = pose.rotation * skew(kZ);  // dR/d yaw = R [z]x
    for (int k = 0; k < 3; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        rotation_rate[kk] = tilt_rate[kk] + u_xi(2, k) * yaw_rate;
        pose_jacobian.position_m.col(k) = Eigen::Vector3d(u_xi(0, k), u_xi(1, k), k == 0);
        pose_jacobian.normal.col(k) = -rotation_rate[kk].col(2);
    }

    const double tilt = std::sqrt(tx * tx + ty * ty);
    jacobian.row(0) =
        tilt > 0.0 ? Eigen::RowVector3d(0.0, -tx / tilt, -ty / tilt) : Eigen::RowVector3d::Zero();
    jacobian.row(1) = Eigen::RowVector3d(1.0 / config_.plate_radius_m, 0.0, 0.0);
    const double crank = config_.geometry.crank_length_m;
    const Eigen::Vector3d towards_body = pose.plateNormal();
    LegSolutions legs;
    if (!solveLegs(pose, legs)) {
        return false;
    }
    for (int leg = 0; leg < 3; ++leg) {
        const auto i = static_cast<std::size_t>(leg);
        const LegSolution& s = legs[i];
        const Eigen::Vector3d rel = s.joint_m - base_joint_[i];
        const double u = radial_[i].dot(rel);
        const double w = rel.z();
        const double rho2 = u * u + w * w;
        const double rho = std::sqrt(rho2);
        const double kappa = (rho2 + crank * crank -
                              config_.geometry.link_length_m * config_.geometry.link_length_m) /
                             (2.0 * crank);
        const double q = kappa / rho;
        const double acos_rate = 1.0 / std::sqrt(std::max(1.0 - q * q, 1e-300));
        const Eigen::Vector3d link = s.elbow_m - s.joint_m;
        const double link_length = link.norm();
        const Eigen::Vector3d l = link / link_length;
        const double cosine = std::clamp(l.dot(towards_body), -1.0, 1.0);
        const double cone_rate = 1.0 / std::sqrt(std::max(1.0 - cosine * cosine, 1e-300));
        const Eigen::Vector3d elbow_rate =
            crank * (-std::sin(s.servo_rad) * radial_[i] + std::cos(s.servo_rad) * kZ);
        for (int k = 0; k < 3; ++k) {
            const auto kk = static_cast<std::size_t>(k);
            const Eigen::Vector3d joint_rate =
                pose_jacobian.position_m.col(k) + rotation_rate[kk] * platform_arm_[i];
            const double du = radial_[i].dot(joint_rate);
            const double dw = joint_rate.z();
            const double drho = (u * du + w * dw) / rho;
            const double dkappa = (u * du + w * dw) / crank;
            const double dq = (dkappa * rho - kappa * drho) / rho2;
            const double dservo = (u * dw - w * du) / rho2 + acos_rate * dq;
            const Eigen::Vector3d dlink = elbow_rate * dservo - joint_rate;
            const Eigen::Vector3d dl = (dlink - l * l.dot(dlink)) / link_length;
            const double dcosine = dl.dot(towards_body) + l.dot(pose_jacobian.normal.col(k));
            jacobian(2 + leg, k) = dservo;
            jacobian(5 + leg, k) = -dservo;
            jacobian(8 + leg, k) = -(q < 0.0 ? -dq : dq);
            jacobian(11 + leg, k) = cone_rate * dcosine;
        }
    }
    return true;
}

bool ThimbleKinematics::feasible(const ConstraintValues& values) noexcept {
    return std::all_of(values.begin(), values.end(), [](double v) { return v >= 0.0; });
}

bool ThimbleKinematics::isFeasible(const PlatformDofs& dofs) const noexcept {
    ConstraintValues values;
    return constraints(dofs, values) && feasible(values);
}

InverseResult ThimbleKinematics::inverse(const PlatformDofs& dofs,
                                         bool check_workspace) const noexcept {
    InverseResult out;
    out.error = platformPose(dofs, out.pose);
    if (!out.ok()) {
        return out;
    }
    LegSolutions legs;
    if (!solveLegs(out.pose, legs, &out.leg)) {
        out.error = KinematicsError::kLegUnreachable;
        return out;
    }
    for (std::size_t i = 0; i < 3; ++i) {
        out.servo_rad[i] = legs[i].servo_rad;
    }
    if (!check_workspace) {
        return out;
    }
    ConstraintValues values;
    (void)constraints(dofs, values);
    static constexpr std::array<KinematicsError, 4> kGroupError{
        KinematicsError::kServoBelowMin, KinematicsError::kServoAboveMax,
        KinematicsError::kReachMargin, KinematicsError::kJointCone};
    if (values[0] < 0.0) {
        out.error = KinematicsError::kTiltLimit;
    } else if (values[1] < 0.0) {
        out.error = KinematicsError::kIndentationLimit;
    } else {
        for (int index = 2; index < kConstraintCount; ++index) {
            if (values[static_cast<std::size_t>(index)] < 0.0) {
                out.error = kGroupError[static_cast<std::size_t>((index - 2) / 3)];
                out.leg = (index - 2) % 3;
                break;
            }
        }
    }
    return out;
}

ForwardResult ThimbleKinematics::forward(const ServoAngles& measured_rad,
                                         const PlatformDofs& guess) const noexcept {
    // Newton from the guess, then from the workspace's centre, then from the retract pose.
    // From the centre alone it stalled on about 3 in 100 000 reachable poses, all high and
    // tilted by 0.2-0.35 rad (a step that no halving could make decrease the residual); from
    // the retract pose each of those converged. A second and third start cost only when the
    // first fails: at most three solves.
    ForwardResult out = forwardFrom(measured_rad, guess);
    if (out.ok() || out.error == KinematicsError::kNonFinite) {
        return out;
    }
    for (const PlatformDofs* start : {&centre_, &retract_}) {
        if (start->height_m == guess.height_m && start->tilt_x_rad == guess.tilt_x_rad &&
            start->tilt_y_rad == guess.tilt_y_rad) {
            continue;
        }
        const int iterations = out.iterations;
        out = forwardFrom(measured_rad, *start);
        out.iterations += iterations;
        if (out.ok()) {
            return out;
        }
    }
    return out;
}

ForwardResult ThimbleKinematics::forwardFrom(const ServoAngles& measured_rad,
                                             const PlatformDofs& guess) const noexcept {
    ForwardResult out;
    if (!std::all_of(measured_rad.begin(), measured_rad.end(),
                     [](double v) { return std::isfinite(v); })) {
        out.error = KinematicsError::kNonFinite;
        return out;
    }
    const Eigen::Vector3d measured(measured_rad[0], measured_rad[1], measured_rad[2]);
    auto toVector = [](const PlatformDofs& d) {
        return Eigen::Vector3d(d.height_m, d.tilt_x_rad, d.tilt_y_rad);
    };
    auto toDofs = [](const Eigen::Vector3d& v) { return PlatformDofs{v.x(), v.y(), v.z()}; };
    auto residualAt = [&](const Eigen::Vector3d& xi, Eigen::Vector3d& residual) {
        ServoAngles angles;
        if (!rawServoAngles(toDofs(xi), angles)) {
            return false;
        }
        residual = Eigen::Vector3d(angles[0], angles[1], angles[2]) - measured;
        return true;
    };
    Eigen::Vector3d xi = toVector(finite(guess) && isFeasible(guess) ? guess : centre_);
    Eigen::Vector3d residual;
    if (!residualAt(xi, residual)) {
        xi = toVector(centre_);
        if (!residualAt(xi, residual)) {
            out.error = KinematicsError::kForwardNotConverged;
            return out;
        }
    }
    // Central differences: the residual is smooth and the step is far above round-off, so
    // the Jacobian is accurate to ~1e-9 and Newton still converges quadratically enough.
    const Eigen::Vector3d step(1e-7, 1e-6, 1e-6);
    for (out.iterations = 0; out.iterations < kForwardMaxIterations; ++out.iterations) {
        out.residual_rad = residual.cwiseAbs().maxCoeff();
        if (out.residual_rad < kForwardToleranceRad) {
            out.dofs = toDofs(xi);
            out.error = platformPose(out.dofs, out.pose);
            return out;
        }
        Eigen::Matrix3d jacobian;
        for (int k = 0; k < 3; ++k) {
            Eigen::Vector3d plus = xi;
            Eigen::Vector3d minus = xi;
            plus(k) += step(k);
            minus(k) -= step(k);
            Eigen::Vector3d r_plus;
            Eigen::Vector3d r_minus;
            if (!residualAt(plus, r_plus) || !residualAt(minus, r_minus)) {
                out.error = KinematicsError::kForwardNotConverged;
                return out;
            }
            jacobian.col(k) = (r_plus - r_minus) / (2.0 * step(k));
        }
        const Eigen::Vector3d delta = jacobian.partialPivLu().solve(residual);
        // Backtrack while the legs cannot close or the residual grows.
        double alpha = 1.0;
        bool accepted = false;
        for (int halving = 0; halving < 30 && !accepted; ++halving, alpha *= 0.5) {
            const Eigen::Vector3d candidate = xi - alpha * delta;
            Eigen::Vector3d candidate_residual;
            if (residualAt(candidate, candidate_residual) &&
                candidate_residual.cwiseAbs().maxCoeff() < out.residual_rad) {
                xi = candidate;
                residual = candidate_residual;
                accepted = true;
            }
        }
        if (!accepted) {
            break;
        }
    }
    out.residual_rad = residual.cwiseAbs().maxCoeff();
    out.dofs = toDofs(xi);
    out.error = out.residual_rad < kForwardToleranceRad ? platformPose(out.dofs, out.pose)
                                                        : KinematicsError::kForwardNotConverged;
    return out;
}

PlatformDofs ThimbleKinematics::projectToWorkspace(const PlatformDofs& dofs) const noexcept {
    if (!finite(dofs)) {
        return retract_;
    }
    if (isFeasible(dofs)) {
        return dofs;
    }
    PlatformDofs clamped = dofs;
    const double tilt = std::hypot(dofs.tilt_x_rad, dofs.tilt_y_rad);
    if (tilt > config_.max_tilt_rad) {
        clamped.tilt_x_rad *= config_.max_tilt_rad / tilt;
        clamped.tilt_y_rad *= config_.max_tilt_rad / tilt;
    }
    clamped.height_m = std::clamp(dofs.height_m, summary_.min_height_m, summary_.max_height_m);
    if (isFeasible(clamped)) {
        return clamped;
    }
    PlatformDofs inside{clamped.height_m, 0.0, 0.0};
    if (!isFeasible(inside)) {
        inside = retract_;
    }
    // Bisection on the segment inside -> clamped: the farthest feasible point.
    double lo = 0.0;
    double hi = 1.0;
    for (int i = 0; i < 24; ++i) {  // 6e-8 of the segment
        const double mid = 0.5 * (lo + hi);
        const PlatformDofs candidate{
            inside.height_m + mid * (clamped.height_m - inside.height_m),
            inside.tilt_x_rad + mid * (clamped.tilt_x_rad - inside.tilt_x_rad),
            inside.tilt_y_rad + mid * (clamped.tilt_y_rad - inside.tilt_y_rad)};
        (isFeasible(candidate) ? lo : hi) = mid;
    }
    return PlatformDofs{inside.height_m + lo * (clamped.height_m - inside.height_m),
                        inside.tilt_x_rad + lo * (clamped.tilt_x_rad - inside.tilt_x_rad),
                        inside.tilt_y_rad + lo * (clamped.tilt_y_rad - inside.tilt_y_rad)};
}

void ThimbleKinematics::computeWorkspace() {
    // Scan the zero-tilt heights on a fine grid, then refine both ends by bisection. The
    // feasible set along this line is an interval for any sane geometry.
    const double lowest = min_height_m_;
    const double highest = config_.geometry.link_length_m + config_.geometry.crank_length_m +
                           config_.geometry.base_radius_m;
    constexpr int kSteps = 400;
    double first = NAN;
    double last = NAN;
    for (int k = 0; k <= kSteps; ++k) {
        const double h = lowest + (highest - lowest) * k / kSteps;
        if (isFeasible({h, 0.0, 0.0})) {
            if (std::isnan(first)) {
                first = h;
            }
            last = h;
        }
    }
    if (std::isnan(first)) {
        // No feasible pose at all: keep everything at the indentation limit so callers see
        // a degenerate workspace; the loader-side geometry checks should prevent this.
        summary_ = WorkspaceSummary{lowest, lowest};
        retract_ = centre_ = PlatformDofs{lowest, 0.0, 0.0};
        return;
    }
    const double dh = (highest - lowest) / kSteps;
    auto refine = [&](double feasible_h, double infeasible_h) {
        for (int i = 0; i < 50; ++i) {
            const double mid = 0.5 * (feasible_h + infeasible_h);
            (isFeasible({mid, 0.0, 0.0}) ? feasible_h : infeasible_h) = mid;
        }
        return feasible_h;
    };
    summary_.min_height_m = first > lowest ? refine(first, first - dh) : first;
    summary_.max_height_m = last < highest ? refine(last, last + dh) : last;
    retract_ = PlatformDofs{summary_.max_height_m, 0.0, 0.0};
    centre_ = PlatformDofs{0.5 * (summary_.min_height_m + summary_.max_height_m), 0.0, 0.0};
}

TiltReach ThimbleKinematics::tiltReach() const noexcept {
    TiltReach reach;
    // Largest tilt reachable in all 72 directions, maximised over the height grid.
    constexpr int kDirections = 72;
    constexpr int kHeights = 40;
    for (int k = 0; k <= kHeights; ++k) {
        const double h =
            summary_.min_height_m + (summary_.max_height_m - summary_.min_height_m) * k / kHeights;
        double worst = config_.max_tilt_rad;
        for (int d = 0; d < kDirections && worst > reach.max_tilt_rad; ++d) {
            const double angle = 2.0 * 3.14159265358979323846 * d / kDirections;
            double lo = 0.0;
            double hi = worst;
            if (isFeasible({h, hi * std::cos(angle), hi * std::sin(angle)})) {
                continue;
            }
            for (int i = 0; i < 30; ++i) {
                const double mid = 0.5 * (lo + hi);
                (isFeasible({h, mid * std::cos(angle), mid * std::sin(angle)}) ? lo : hi) = mid;
            }
            worst = lo;
        }
        if (worst > reach.max_tilt_rad) {
            reach.max_tilt_rad = worst;
            reach.best_height_m = h;
        }
    }
    return reach;
}

PlatformDofs poseForPlane(const ThimbleKinematics& kinematics,
                          const Eigen::Vector3d& normal_into_finger,
                          const Eigen::Vector3d& point_m) noexcept {
    const Eigen::Vector3d normal = normal_into_finger.normalized();
    const auto tilt = tiltForNormal(normal);
    PlatformDofs dofs{point_m.z(), tilt[0], tilt[1]};
    // nu . (q - p(h)) = 0 with dp_z/dh = 1 and a parasitic shift that changes slowly with h.
    for (int i = 0; i < 20; ++i) {
        PlatformPose pose;
        if (kinematics.platformPose(dofs, pose) != KinematicsError::kNone) {
            break;
        }
        const double gap = normal.dot(point_m - pose.position_m);
        dofs.height_m += gap / normal.z();
        if (std::fabs(gap) < 1e-12) {
            break;
        }
    }
    return dofs;
}

}  // namespace haptic::tactile
