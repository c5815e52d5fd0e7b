#include <Eigen/QR>
#include <stdexcept>

#include "haptic/kinesthetic/device_model.hpp"

namespace haptic::kinesthetic {

LinearPointDevice::LinearPointDevice(const Eigen::MatrixXd& actuated_directions, double max_force_n,
                                     double workspace_half_width_m)
    : max_force_n_(max_force_n), half_width_m_(workspace_half_width_m) {
    const auto d = actuated_directions.rows();
    const auto m = actuated_directions.cols();
    if (d != 2 && d != 3) {
        throw std::invalid_argument("LinearPointDevice: dimension must be 2 or 3, got " +
                                    std::to_string(d));
    }
    if (m < 1 || m > d) {
        throw std::invalid_argument("LinearPointDevice: need 1.." + std::to_string(d) +
                                    " actuated directions, got " + std::to_string(m));
    }
    if (!actuated_directions.allFinite()) {
        throw std::invalid_argument("LinearPointDevice: actuated directions contain NaN/Inf");
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(actuated_directions);
    qr.setThreshold(1e-9);
    if (qr.rank() != m) {
        throw std::invalid_argument("LinearPointDevice: actuated directions are rank deficient");
    }
    if (!(max_force_n > 0.0) || !(workspace_half_width_m > 0.0)) {
        throw std::invalid_argument("LinearPointDevice: force and workspace limits must be > 0");
    }
    A_ = actuated_directions;
}

void LinearPointDevice::actuatorCoordinates(const ConfigVector& q,
                                            ActuatorVector& ell) const noexcept {
    ell.noalias() = A_.transpose() * q;
}

void LinearPointDevice::actuationMatrix(const ConfigVector& /*q*/,
                                        ActuationMatrix& B) const noexcept {
    B = A_;
}

void LinearPointDevice::contactPoint(const ConfigVector& q, PointVector& x) const noexcept {
    x = q;
}

ActuatorLimits LinearPointDevice::actuatorLimits(int /*actuator*/) const noexcept {
    return ActuatorLimits{max_force_n_, -half_width_m_, half_width_m_};
}

config::Interval LinearPointDevice::configurationLimits(int /*i*/) const noexcept {
    return config::Interval{-half_width_m_, half_width_m_};
}

}  // namespace haptic::kinesthetic
