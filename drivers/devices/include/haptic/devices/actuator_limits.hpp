#pragma once

// What the exoskeleton's actuator can deliver, as its data sheet (the device file's
// `actuator` block) says: the device behaviour both hapticemu's model and hapticd's
// plausibility check rely on, so that the two cannot drift apart.

#include <algorithm>
#include <cmath>

#include "haptic/config/device.hpp"

namespace haptic::devices {

// The force a drive making `drive_force_n` delivers to a rod moving at `rod_speed_m_per_s`:
// the motor's torque-speed line. Driving the rod along its motion it delivers at most
// actuator.max_force_n (1 - |v| / actuator.max_speed_m_per_s), nothing at max_speed; braking
// it, the full force.
[[nodiscard]] inline double deliverableForceN(double drive_force_n, double rod_speed_m_per_s,
                                              const config::ActuatorConfig& actuator) noexcept {
    if (!(drive_force_n * rod_speed_m_per_s > 0.0) || !(actuator.max_speed_m_per_s > 0.0)) {
        return drive_force_n;
    }
    const double cap = actuator.max_force_n * std::max(0.0, 1.0 - std::abs(rod_speed_m_per_s) /
                                                                      actuator.max_speed_m_per_s);
    return std::clamp(drive_force_n, -cap, cap);
}

}  // namespace haptic::devices
