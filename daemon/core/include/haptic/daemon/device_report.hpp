#pragma once

// What the per-device runtime (daemon/runtime) hands DaemonCore each tick: the measured
// device state from the CAN driver, the bus health and what was commanded. DaemonCore puts
// it into DeviceState, haptic/status and haptic/telemetry. Trivially copyable, no allocation.

#include <array>
#include <cstdint>

#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

struct DeviceReport {
    // False until a runtime reports the device: status then shows it OFFLINE with an
    // unknown bus, as before any driver was attached.
    bool attached{false};
    msgs::DeviceRunState run_state{msgs::DeviceRunState::kOffline};
    msgs::CanCounters can{};
    double last_frame_age_ms{-1.0};  // -1: never heard from the device
    // DeviceStatusBit: kOnline, kSafeState, kFault (the core adds kRendering, kStaleSimInput).
    std::uint32_t status_bits{static_cast<std::uint32_t>(msgs::DeviceStatusBit::kSafeState)};
    // The code of a latched fault whose cause the device still shows (it reports its own
    // fault, stays silent, ...), 0 when none: `clear` is refused while one stands.
    std::uint32_t standing_fault{0};

    // Measured (DeviceState).
    std::array<double, msgs::kMaxJointDofs> joint_position_rad{};
    std::array<double, msgs::kMaxJointDofs> joint_velocity_rad_per_s{};
    std::array<double, msgs::kMaxActuators> actuator_position{};
    std::array<double, msgs::kMaxActuators> actuator_force{};
    std::array<double, 3> platform_position_m{};
    std::array<double, 4> platform_orientation_wxyz{1.0, 0.0, 0.0, 0.0};

    // Commanded and rendered this tick (telemetry), in the part of the device's kind.
    msgs::DeviceKind kind{msgs::DeviceKind::kExoskeleton};
    msgs::ExoskeletonTelemetry exoskeleton{};
    msgs::ThimbleTelemetry thimble{};
};

}  // namespace haptic::daemon
