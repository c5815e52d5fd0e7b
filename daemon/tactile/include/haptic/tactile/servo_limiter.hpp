#pragma once

// Last stage before the thimble's servos (docs/algorithms.md §3.6, servo model): clamps each
// commanded angle to the servo range and limits its rate to servos.max_rate_deg_per_s, so a
// jump of the optimiser (e.g. to the retract pose) becomes a ramp the servo can follow.
// noexcept, allocation-free: called by the 1 kHz loop.

#include "haptic/config/device.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::tactile {

struct LimitedServoCommand {
    ServoAngles servo_rad{};
    bool rate_limited{false};
    bool range_clamped{false};
    bool rejected{false};  // non-finite target or period: the previous command is held
};

class ServoLimiter {
  public:
    // `initial_rad` is where the servos are now (measured), clamped to the range.
    ServoLimiter(const config::ServoConfig& servos, const ServoAngles& initial_rad) noexcept;

    [[nodiscard]] LimitedServoCommand step(const ServoAngles& target_rad, double period_s) noexcept;
    [[nodiscard]] const ServoAngles& last() const noexcept { return last_; }
    // The caller sent `sent_rad` instead of step()'s result (a shorter step towards it): the
    // next step starts from there.
    void holdAt(const ServoAngles& sent_rad) noexcept { last_ = sent_rad; }

  private:
    config::ServoConfig servos_;
    ServoAngles last_{};
};

}  // namespace haptic::tactile
