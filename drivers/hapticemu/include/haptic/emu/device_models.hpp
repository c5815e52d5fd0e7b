#pragma once

// Device dynamics and the user model that hapticemu runs. Deterministic: the same commands
// and time steps give bit-identical states, which is what lets the round-trip tests predict
// every state frame the emulator sends.

#include <array>

#include "haptic/config/device.hpp"
#include "haptic/config/virtual_user.hpp"

namespace haptic::emu {

// Exoskeleton: the actuator force follows the command through a first-order lag, limited to
// actuator.max_force_n and to the torque-speed line (devices::deliverableForceN); it is zero while
// disabled. The finger (MCP, PIP, DIP) follows the user's intent through a hand impedance
// (per-joint inertia, stiffness, damping) and feels the actuator through the linkage: tau = J^T F
// with J = d(stroke)/dq, so a positive force (extending the actuator) flexes the finger. Joints
// stop at their limits. The intent is the virtual user's (setIntent) once it wears the
// device; until then, and for an emulator without a user, a built-in open-close sine.
class ExoskeletonModel {
  public:
    using HandImpedance = config::HandImpedanceConfig;
    // Intent: joint_mid + amplitude * sin(2 pi f t), a slow open-close movement.
    struct Intent {
        double frequency_hz{0.5};
        double amplitude_fraction{0.35};  // of each joint's range, about its middle
    };

    explicit ExoskeletonModel(const config::DeviceConfig& device);
    ExoskeletonModel(const config::DeviceConfig& device, HandImpedance hand, Intent intent);

    void step(double dt_s, double force_command_n, bool enable) noexcept;
    // The drive loses power (a restart): disabled, no current, at once.
    void disable() noexcept {
        enabled_ = false;
        drive_force_n_ = 0.0;
    }
    // The joint angles the user's finger aims for from now on (non-finite values are ignored).
    void setIntent(const std::array<double, 3>& intent_rad) noexcept;
    void setHandImpedance(const HandImpedance& hand) noexcept { hand_ = hand; }
    // Places the finger at rest at `q_rad` (clamped to the joint limits).
    void placeFinger(const std::array<double, 3>& q_rad) noexcept;

    [[nodiscard]] double forceN() const noexcept { return force_n_; }
    // The rod's speed the last step()'s force was delivered at (m/s, positive lengthening).
    [[nodiscard]] double rodSpeedMPerS() const noexcept { return rod_speed_m_per_s_; }
    [[nodiscard]] double strokeM() const noexcept;
    [[nodiscard]] const std::array<double, 3>& jointRad() const noexcept { return q_rad_; }
    [[nodiscard]] bool enabled() const noexcept { return enabled_; }
    [[nodiscard]] bool atStrokeMin() const noexcept;
    [[nodiscard]] bool atStrokeMax() const noexcept;
    [[nodiscard]] double timeS() const noexcept { return time_s_; }
    // stroke(q) of the linkage and its gradient d(stroke)/dq (config LinkageConfig).
    [[nodiscard]] double linkageStrokeM(const std::array<double, 3>& q_rad,
                                        std::array<double, 3>* gradient) const noexcept;

  private:
    config::ActuatorConfig actuator_;
    config::FingerConfig finger_;
    config::LinkageConfig linkage_;
    HandImpedance hand_;
    Intent intent_;
    bool user_intent_{false};
    std::array<double, 3> user_intent_rad_{};
    double drive_force_n_{0.0};  // the force the drive's current makes, after its lag
    double rod_speed_m_per_s_{0.0};
    double force_n_{0.0};  // what reaches the rod: drive_force_n_ on the torque-speed line
    bool enabled_{false};
    double time_s_{0.0};
    std::array<double, 3> q_rad_{};
    std::array<double, 3> qd_rad_per_s_{};
};

// Thimble: each servo moves towards its target with a first-order lag whose speed is capped
// at servos.max_rate; targets are clamped to the servo range. It powers on at the retract pose.
class ThimbleModel {
  public:
    explicit ThimbleModel(const config::DeviceConfig& device);

    void step(double dt_s, const std::array<double, 3>& target_rad) noexcept;
    [[nodiscard]] const std::array<double, 3>& angleRad() const noexcept { return angle_rad_; }

  private:
    config::ServoConfig servos_;
    std::array<double, 3> angle_rad_{};
};

}  // namespace haptic::emu
