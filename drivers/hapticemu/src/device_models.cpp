#include "haptic/emu/device_models.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "haptic/devices/actuator_limits.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {

ExoskeletonModel::ExoskeletonModel(const config::DeviceConfig& device)
    : ExoskeletonModel(device, HandImpedance{}, Intent{}) {}

ExoskeletonModel::ExoskeletonModel(const config::DeviceConfig& device, HandImpedance hand,
                                   Intent intent)
    : hand_(hand), intent_(intent) {
    if (!device.isExoskeleton()) {
        throw std::invalid_argument("exoskeleton model: device '" + device.name +
                                    "' is not an exoskeleton");
    }
    actuator_ = device.exoskeleton().actuator;
    finger_ = device.exoskeleton().finger;
    linkage_ = device.exoskeleton().linkage;
    for (std::size_t j = 0; j < 3; ++j) {
        const config::Interval& limits = finger_.joint_limits_rad[j];
        q_rad_[j] = 0.5 * (limits.min + limits.max);
    }
}

double ExoskeletonModel::linkageStrokeM(const std::array<double, 3>& q_rad,
                                        std::array<double, 3>* gradient) const noexcept {
    const double c = std::cos(q_rad[0]);
    const double s = std::sin(q_rad[0]);
    const double px = linkage_.proximal_attachment_m[0];
    const double py = linkage_.proximal_attachment_m[1];
    const double dx = c * px - s * py - linkage_.actuator_base_m[0];
    const double dy = s * px + c * py - linkage_.actuator_base_m[1];
    const double span = std::hypot(dx, dy);
    if (gradient != nullptr) {
        // d/dq1 of R(q1) p is (-s px - c py, c px - s py).
        const double ddx = -s * px - c * py;
        const double ddy = c * px - s * py;
        (*gradient)[0] = span > 0.0 ? (dx * ddx + dy * ddy) / span : 0.0;
        (*gradient)[1] = linkage_.distal_coupling_m_per_rad[0];
        (*gradient)[2] = linkage_.distal_coupling_m_per_rad[1];
    }
    return span - linkage_.rod_length_m + linkage_.distal_coupling_m_per_rad[0] * q_rad[1] +
           linkage_.distal_coupling_m_per_rad[1] * q_rad[2];
}

double ExoskeletonModel::strokeM() const noexcept {
    return std::clamp(linkageStrokeM(q_rad_, nullptr), actuator_.stroke_min_m,
                      actuator_.stroke_max_m);
}

bool ExoskeletonModel::atStrokeMin() const noexcept {
    return linkageStrokeM(q_rad_, nullptr) <= actuator_.stroke_min_m;
}

bool ExoskeletonModel::atStrokeMax() const noexcept {
    return linkageStrokeM(q_rad_, nullptr) >= actuator_.stroke_max_m;
}

void ExoskeletonModel::setIntent(const std::array<double, 3>& intent_rad) noexcept {
    for (std::size_t j = 0; j < 3; ++j) {
        if (std::isfinite(intent_rad[j])) {
            user_intent_rad_[j] = intent_rad[j];
        }
    }
    user_intent_ = true;
}

void ExoskeletonModel::placeFinger(const std::array<double, 3>& q_rad) noexcept {
    for (std::size_t j = 0; j < 3; ++j) {
        const config::Interval& limits = finger_.joint_limits_rad[j];
        if (std::isfinite(q_rad[j])) {
            q_rad_[j] = std::clamp(q_rad[j], limits.min, limits.max);
        }
        qd_rad_per_s_[j] = 0.0;
    }
}

void ExoskeletonModel::step(double dt_s, double force_command_n, bool enable) noexcept {
    if (!(dt_s > 0.0)) {
        return;
    }
    enabled_ = enable;
    double target_n = 0.0;
    if (enable && std::isfinite(force_command_n)) {
        target_n = std::clamp(force_command_n, -actuator_.max_force_n, actuator_.max_force_n);
    }
    if (enable) {
        // Implicit Euler of tau dF/dt = target - F: stable for any dt.
        drive_force_n_ +=
            (target_n - drive_force_n_) * dt_s / (actuator_.lag_time_constant_s + dt_s);
    } else {
        drive_force_n_ = 0.0;  // a disabled drive carries no current: limp at once, no lag
    }
    time_s_ += dt_s;

    std::array<double, 3> jacobian{};
    (void)linkageStrokeM(q_rad_, &jacobian);
    const double phase = std::sin(2.0 * std::numbers::pi * intent_.frequency_hz * time_s_);
    // The rod's own damping b, reflected to the joints as b B B^T: its diagonal is implicit
    // with the finger's damping, the coupling between joints explicit (one step behind).
    const double rod_damping = actuator_.damping_n_s_per_m;
    double rod_speed_m_per_s = 0.0;
    for (std::size_t j = 0; j < 3; ++j) {
        rod_speed_m_per_s += jacobian[j] * qd_rad_per_s_[j];
    }
    rod_speed_m_per_s_ = rod_speed_m_per_s;
    force_n_ = devices::deliverableForceN(drive_force_n_, rod_speed_m_per_s, actuator_);
    for (std::size_t j = 0; j < 3; ++j) {
        const config::Interval& limits = finger_.joint_limits_rad[j];
        const double mid = 0.5 * (limits.min + limits.max);
        const double intent_rad =
            user_intent_ ? user_intent_rad_[j]
                         : mid + intent_.amplitude_fraction * (limits.max - limits.min) * phase;
        // Spring and actuator explicitly, damping implicitly: stable for stiff fingers.
        const double other_joints_rod_speed = rod_speed_m_per_s - jacobian[j] * qd_rad_per_s_[j];
        const double torque = hand_.stiffness_nm_per_rad[j] * (intent_rad - q_rad_[j]) +
                              jacobian[j] * (force_n_ - rod_damping * other_joints_rod_speed);
        const double inertia = hand_.inertia_kg_m2[j];
        const double damping =
            hand_.damping_nms_per_rad[j] + rod_damping * jacobian[j] * jacobian[j];
        qd_rad_per_s_[j] =
            (inertia * qd_rad_per_s_[j] + dt_s * torque) / (inertia + dt_s * damping);
        q_rad_[j] += dt_s * qd_rad_per_s_[j];
        if (q_rad_[j] < limits.min) {
            q_rad_[j] = limits.min;
            qd_rad_per_s_[j] = std::max(qd_rad_per_s_[j], 0.0);
        } else if (q_rad_[j] > limits.max) {
            q_rad_[j] = limits.max;
            qd_rad_per_s_[j] = std::min(qd_rad_per_s_[j], 0.0);
        }
    }
}

ThimbleModel::ThimbleModel(const config::DeviceConfig& device) {
    if (!device.isThimble()) {
        throw std::invalid_argument("thimble model: device '" + device.name + "' is not a thimble");
    }
    servos_ = device.thimble().servos;
    // Powered on, the servos stand where the plate is farthest from the pad (the retract
    // pose), as a device's firmware would home them: anywhere else would press the finger of a
    // user who put the thimble on before hapticd came up (0 rad on the shipped geometry is a
    // plate 12 mm into the pad). A geometry without a retract pose starts at 0 rad.
    const tactile::ThimbleKinematics kinematics(device.thimble());
    const tactile::InverseResult retract = kinematics.inverse(kinematics.retractPose(), false);
    for (std::size_t i = 0; i < angle_rad_.size(); ++i) {
        angle_rad_[i] =
            std::clamp(retract.ok() ? retract.servo_rad[i] : 0.0, servos_.min_rad, servos_.max_rad);
    }
}

void ThimbleModel::step(double dt_s, const std::array<double, 3>& target_rad) noexcept {
    if (!(dt_s > 0.0)) {
        return;
    }
    const double max_step = servos_.max_rate_rad_per_s * dt_s;
    for (std::size_t i = 0; i < 3; ++i) {
        if (!std::isfinite(target_rad[i])) {
            continue;  // hold position
        }
        const double target = std::clamp(target_rad[i], servos_.min_rad, servos_.max_rad);
        const double lagged =
            (target - angle_rad_[i]) * dt_s / (servos_.lag_time_constant_s + dt_s);
        angle_rad_[i] += std::clamp(lagged, -max_step, max_step);
    }
}

}  // namespace haptic::emu
