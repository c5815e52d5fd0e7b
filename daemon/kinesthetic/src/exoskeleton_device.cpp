#include <cmath>
#include <stdexcept>

#include "haptic/kinesthetic/device_model.hpp"

namespace haptic::kinesthetic {

namespace {

struct ProximalLever {
    Eigen::Vector2d d;       // R(theta_1) p - a: actuator axis, base pivot to rod-end pivot
    Eigen::Vector2d dd_dq1;  // R'(theta_1) p
};

ProximalLever proximalLever(const config::LinkageConfig& linkage, double theta1) noexcept {
    const Eigen::Vector2d p(linkage.proximal_attachment_m[0], linkage.proximal_attachment_m[1]);
    const Eigen::Vector2d a(linkage.actuator_base_m[0], linkage.actuator_base_m[1]);
    const double c = std::cos(theta1);
    const double s = std::sin(theta1);
    const Eigen::Vector2d rotated(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    return ProximalLever{rotated - a, Eigen::Vector2d(-rotated.y(), rotated.x())};
}

}  // namespace

ExoskeletonDevice::ExoskeletonDevice(const config::ExoskeletonConfig& exo) : exo_(exo) {
    for (double length : exo.finger.phalanx_lengths_m) {
        if (!(length > 0.0) || !std::isfinite(length)) {
            throw std::invalid_argument("ExoskeletonDevice: phalanx lengths must be > 0");
        }
    }
    if (!(exo.actuator.max_force_n > 0.0)) {
        throw std::invalid_argument("ExoskeletonDevice: actuator.max_force_n must be > 0");
    }
    const auto& linkage = exo.linkage;
    const double pivot_separation =
        std::hypot(linkage.proximal_attachment_m[0], linkage.proximal_attachment_m[1]) +
        std::hypot(linkage.actuator_base_m[0], linkage.actuator_base_m[1]);
    if (!(pivot_separation > 0.0)) {
        throw std::invalid_argument("ExoskeletonDevice: linkage pivots coincide");
    }
}

void ExoskeletonDevice::actuatorCoordinates(const ConfigVector& q,
                                            ActuatorVector& ell) const noexcept {
    const auto& linkage = exo_.linkage;
    const ProximalLever lever = proximalLever(linkage, q[0]);
    ell.resize(1);
    ell[0] = lever.d.norm() - linkage.rod_length_m + linkage.distal_coupling_m_per_rad[0] * q[1] +
             linkage.distal_coupling_m_per_rad[1] * q[2];
}

void ExoskeletonDevice::actuationMatrix(const ConfigVector& q, ActuationMatrix& B) const noexcept {
    const auto& linkage = exo_.linkage;
    const ProximalLever lever = proximalLever(linkage, q[0]);
    const double length = lever.d.norm();
    B.resize(3, 1);
    // A degenerate pose with coincident pivots has no defined lever arm; report none.
    B(0, 0) = length > 1e-12 ? lever.d.dot(lever.dd_dq1) / length : 0.0;
    B(1, 0) = linkage.distal_coupling_m_per_rad[0];
    B(2, 0) = linkage.distal_coupling_m_per_rad[1];
}

void ExoskeletonDevice::contactPoint(const ConfigVector& q, PointVector& x) const noexcept {
    x.setZero(2);
    double phi = 0.0;
    for (int k = 0; k < 3; ++k) {
        phi += q[k];
        x[0] += exo_.finger.phalanx_lengths_m[k] * std::cos(phi);
        x[1] += exo_.finger.phalanx_lengths_m[k] * std::sin(phi);
    }
}

ActuatorLimits ExoskeletonDevice::actuatorLimits(int /*actuator*/) const noexcept {
    return ActuatorLimits{exo_.actuator.max_force_n, exo_.actuator.stroke_min_m,
                          exo_.actuator.stroke_max_m};
}

config::Interval ExoskeletonDevice::configurationLimits(int i) const noexcept {
    return exo_.finger.joint_limits_rad[static_cast<std::size_t>(i)];
}

}  // namespace haptic::kinesthetic
