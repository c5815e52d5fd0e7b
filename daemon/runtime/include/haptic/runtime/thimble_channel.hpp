#pragma once

// The thimble's tick: the newest accepted ContactSurface -> ContactSurfaceOptimiser (solved
// once per new surface; a surface does not change between sim frames) -> fade -> IK ->
// ServoLimiter (servo range, servos.max_rate_deg_per_s) -> servo targets.
//
// "Fade to zero" on a thimble is the plate moving away from the pad: the commanded platform
// pose is blended in (height, tilt_x, tilt_y) between the retract pose (zero tilt, highest
// reachable plate: no contact) and the optimised pose,
//     xi = xi_retract + g (xi_solved - xi_retract),   g = DaemonCore::outputGain,
// so g = 1 is the rendered contact, g = 0 the retract pose, and a falling g lifts and levels
// the plate monotonically, which for the pad's monotone pressure law lowers the contact
// force. The servo limiter then caps how fast the servos move. IDLE, FAULT, E-STOP and a
// device held safe use g = 0: the thimble's safe state is the retract pose. If the blended
// pose has no IK solution the servo angles themselves are blended (always inside the range).

#include <cstdint>

#include "haptic/devices/thimble_driver.hpp"
#include "haptic/runtime/contradiction_timer.hpp"
#include "haptic/runtime/device_channel.hpp"
#include "haptic/tactile/contact_optimiser.hpp"
#include "haptic/tactile/pad_safety.hpp"
#include "haptic/tactile/servo_limiter.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::runtime {

class ThimbleChannel final
    : public DriverChannel<devices::ThimbleDriver, protocol::ThimbleCommand> {
  public:
    // Throws std::invalid_argument when the device is not a thimble.
    ThimbleChannel(const config::DeviceConfig& device, can::CanBus& bus,
                   const ChannelSettings& settings);

    void compute(daemon::DaemonCore& core, std::size_t index,
                 std::int64_t now_ns) noexcept override;

    [[nodiscard]] const tactile::ServoAngles& retractServoAngles() const noexcept {
        return retract_servo_rad_;
    }
    [[nodiscard]] const tactile::SolveReport& lastSolve() const noexcept { return solved_.report; }
    // What the safety limits let through this tick: the blend gain, the pad model's force at
    // the pose the servo targets sent put the plate, and which limit held it back.
    [[nodiscard]] const tactile::PadLimit& padLimit() const noexcept { return pad_limit_; }

  protected:
    void commandSafe() noexcept override { command_.servo_target_rad = retract_servo_rad_; }
    std::uint32_t plausibilityFaults(std::int64_t now_ns) noexcept override;
    [[nodiscard]] bool contradictionPending() const noexcept override {
        return angle_mismatch_.contradicting();
    }
    [[nodiscard]] const char* implausibleMessage() const noexcept override {
        return implausible_message_;
    }

  private:
    void measure() noexcept;
    [[nodiscard]] tactile::PlatformDofs blendDofs(double gain) const noexcept;
    [[nodiscard]] tactile::ServoAngles blend(double gain) const noexcept;

    tactile::ThimbleKinematics kinematics_;
    tactile::ContactSurfaceOptimiser optimiser_;
    tactile::ServoAngles retract_servo_rad_{};
    tactile::PadSafetyLimiter pad_limiter_;
    tactile::ServoLimiter limiter_;
    tactile::PadLimit pad_limit_{};
    tactile::PlatformDofs sent_dofs_{};  // forward kinematics of the last servo targets sent
    tactile::TactileCommand solved_{};
    std::uint64_t solved_from_{0};  // DaemonCore::acceptedCount of the surface solved
    std::uint64_t state_updates_{0};
    tactile::PlatformDofs measured_dofs_{};
    tactile::PlatformPose measured_pose_{};
    // Where the servos should be: the commanded targets through their lag and rate limit,
    // resynchronised to the measured angles whenever the state cannot be judged.
    tactile::ServoAngles expected_servo_rad_{};
    bool expected_synced_{false};
    std::int64_t expected_at_ns_{0};
    double servo_lag_s_{0.0};
    double servo_max_rate_rad_per_s_{0.0};
    double angle_tolerance_rad_{0.0};
    ContradictionTimer angle_mismatch_;
    char implausible_message_[msgs::kShortTextCapacity]{};
};

}  // namespace haptic::runtime
