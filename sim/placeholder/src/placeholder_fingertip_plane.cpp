#include "haptic/sim/placeholder_fingertip_plane.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace haptic::sim {

PlaceholderFingertipPlane::PlaceholderFingertipPlane(const PlaceholderFingerParameters& parameters)
    : parameters_(parameters),
      q_rad_(parameters.rest_rad[0], parameters.rest_rad[1], parameters.rest_rad[2]) {
    // At full press (half a period) the tip must sit press_depth_m below the plane.
    setTime(0.5 * parameters_.press_period_s);
    plane_z_m_ = fingertipPosition().z() + parameters_.press_depth_m;
    setTime(0.0);
    pad_samples_D_.push_back(Eigen::Vector3d(0.0, 0.0, parameters_.pad_depth_m));
    for (int ring = 1; ring <= parameters_.pad_rings; ++ring) {
        const double radius = parameters_.pad_radius_m * ring / parameters_.pad_rings;
        for (int k = 0; k < 8; ++k) {
            const double angle = 2.0 * std::numbers::pi * k / 8.0;
            pad_samples_D_.push_back(Eigen::Vector3d(
                radius * std::cos(angle), radius * std::sin(angle), parameters_.pad_depth_m));
        }
    }
}

void PlaceholderFingertipPlane::setTime(double t_s) noexcept {
    // 0 -> 1 -> 0 over one period, smooth at both ends.
    const double phase =
        0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * t_s / parameters_.press_period_s));
    for (int i = 0; i < 3; ++i) {
        q_rad_[i] = parameters_.rest_rad[static_cast<std::size_t>(i)] +
                    phase * parameters_.press_amplitude_rad[static_cast<std::size_t>(i)];
    }
}

Eigen::Vector3d PlaceholderFingertipPlane::fingertipPosition() const noexcept {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double phi = 0.0;
    for (int i = 0; i < 3; ++i) {
        phi += q_rad_[i];
        const double length = parameters_.phalanx_lengths_m[static_cast<std::size_t>(i)];
        p += length * Eigen::Vector3d(std::cos(phi), 0.0, -std::sin(phi));
    }
    return p;
}

double PlaceholderFingertipPlane::fingertipDistance() const noexcept {
    return fingertipPosition().z() - plane_z_m_;
}

Eigen::Vector3d PlaceholderFingertipPlane::distanceGradient() const noexcept {
    // z = -sum_i l_i sin(phi_i), phi_i = q_1 + ... + q_i, so dz/dq_j = -sum_{i>=j} l_i cos(phi_i).
    std::array<double, 3> phi{};
    double sum = 0.0;
    for (std::size_t i = 0; i < 3; ++i) {
        sum += q_rad_[static_cast<Eigen::Index>(i)];
        phi[i] = sum;
    }
    Eigen::Vector3d gradient;
    for (std::size_t j = 0; j < 3; ++j) {
        double value = 0.0;
        for (std::size_t i = j; i < 3; ++i) {
            value -= parameters_.phalanx_lengths_m[i] * std::cos(phi[i]);
        }
        gradient[static_cast<Eigen::Index>(j)] = value;
    }
    return gradient;
}

void PlaceholderFingertipPlane::fillConstraintSet(msgs::ConstraintSet& out) const noexcept {
    out.dof = 3;
    out.q_sim_rad.fill(0.0);
    out.constraints.clear();
    const double distance = fingertipDistance();
    const Eigen::Vector3d a = distanceGradient();
    Eigen::Vector3d q_sim = q_rad_;
    // Linearised non-penetration: d(q0) + a^T (q - q0) >= 0  <=>  a^T q >= a^T q0 - d(q0).
    const double b = a.dot(q_rad_) - distance;
    if (distance < parameters_.contact_margin_m) {
        msgs::LinearConstraint constraint;
        for (int i = 0; i < 3; ++i) {
            constraint.a[static_cast<std::size_t>(i)] = a[i];
        }
        constraint.b = b;
        out.constraints.push_back(constraint);
        if (distance < 0.0) {
            // Identity-metric projection onto the half-space: the rigid finger stops at the
            // plane (to first order).
            q_sim += a * (b - a.dot(q_rad_)) / a.squaredNorm();
        }
    }
    for (int i = 0; i < 3; ++i) {
        out.q_sim_rad[static_cast<std::size_t>(i)] = q_sim[i];
    }
}

Eigen::Matrix3d PlaceholderFingertipPlane::rotationWorldFromDevice() const noexcept {
    // Straight finger: x_D = x_W, z_D = -z_W (nail to pad points down). Flexion by the
    // distal phalanx's absolute angle rotates D about y_W.
    const double phi = q_rad_.sum();
    const Eigen::Matrix3d flip =
        Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Matrix3d flex =
        Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitY()).toRotationMatrix();
    return flex * flip;
}

Eigen::Vector3d PlaceholderFingertipPlane::deviceOriginWorld() const noexcept {
    // Middle of the distal phalanx, on its centre line; the pad depth puts samples below it.
    const double phi = q_rad_.sum();
    const Eigen::Vector3d axis(std::cos(phi), 0.0, -std::sin(phi));
    return fingertipPosition() - 0.5 * parameters_.phalanx_lengths_m[2] * axis;
}

void PlaceholderFingertipPlane::fillContactSurface(msgs::ContactSurface& out) const noexcept {
    out.samples.clear();
    const Eigen::Matrix3d R_WD = rotationWorldFromDevice();
    const Eigen::Vector3d p_WD = deviceOriginWorld();
    const Eigen::Vector3d normal_D = R_WD.transpose() * Eigen::Vector3d::UnitZ();
    for (const Eigen::Vector3d& p_D : pad_samples_D_) {
        const Eigen::Vector3d p_W = p_WD + R_WD * p_D;
        msgs::ContactSample sample;
        for (int i = 0; i < 3; ++i) {
            sample.p_device_m[static_cast<std::size_t>(i)] = p_D[i];
            sample.normal_device[static_cast<std::size_t>(i)] = normal_D[i];
        }
        sample.signed_distance_m = p_W.z() - plane_z_m_;
        sample.weight = 1.0 / static_cast<double>(pad_samples_D_.size());
        out.samples.push_back(sample);
    }
}

}  // namespace haptic::sim
