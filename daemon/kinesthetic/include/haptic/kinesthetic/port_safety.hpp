#pragma once

// Safety stage for one actuator port, applied after the renderer every 1 kHz tick
// (ALGORITHMS §5.7.3, §6.9): NaN/Inf rejection, time-domain passivity observer/controller
// (Hannaford-Ryu), fade to zero on stale input, force and force-rate saturation.
// Everything is noexcept, allocation- and lock-free, O(1).

#include <cstdint>
#include <limits>

namespace haptic::kinesthetic {

// Energy bookkeeping of the port, sign convention of §5.7.3: u acts along increasing ell; the
// energy absorbed by the rendered environment is E += -u_applied(k-1) (ell_k - ell_{k-1})
// (zero-order hold: the force applied during a period times the motion over that period).
// E < 0 means the rendering has given the user net energy. Two things keep E >= 0 although
// the motion over the next period is unknown and the force can only ramp at the rate limit:
// (1) |u| is capped so that the reserve E, after the next period, still pays for ramping u to
// zero at the rate limit should the motion reverse (|v| u^2 / (2 rate)); a force along the
// motion is budgeted at twice the last displacement, one against it earns its next period;
// (2) a remaining deficit is damped out, b = -(E - u v T) / (T v^2) up to max_damping.
// The cost is the classic one of passivity control: a wall that has not stored energy yet
// (first contact, fast reversals) renders less force for a few milliseconds.
class PassivityController {
  public:
    // max_force_rate: the slew limit applied after this controller (infinity if none).
    PassivityController(double period_s, double max_damping,
                        double max_force_rate = std::numeric_limits<double>::infinity()) noexcept;

    // Start of a tick: the measured actuator coordinate. Returns the velocity estimate.
    double observe(double ell) noexcept;
    // Force corrected for passivity (the input when disabled or nothing to correct).
    [[nodiscard]] double correct(double u_desired) const noexcept;
    // End of a tick: the force actually applied (after every other limit).
    void record(double u_applied) noexcept { u_applied_ = u_applied; }

    void setEnabled(bool enabled) noexcept { enabled_ = enabled; }
    [[nodiscard]] bool enabled() const noexcept { return enabled_; }
    void reset() noexcept;

    // Energy absorbed by the environment so far (J); its negative is what the device generated.
    [[nodiscard]] double observedEnergy() const noexcept { return energy_; }

  private:
    double period_s_;
    double max_damping_;
    double max_rate_;
    double energy_{0.0};
    double ell_previous_{0.0};
    double velocity_{0.0};
    double u_applied_{0.0};
    bool has_previous_{false};
    bool enabled_{true};
};

// Clamp to [-max_force, max_force], then limit the change from `previous` to max_rate * period.
[[nodiscard]] double saturateForce(double u, double previous, double max_force, double max_rate,
                                   double period_s) noexcept;

// Gain in [0, 1] that ramps to zero over fade_time while the input is stale (or invalid) and
// back to one at the same rate once it is fresh, so the force never steps.
class StaleInputFade {
  public:
    StaleInputFade(double period_s, double fade_time_s) noexcept;
    double update(bool input_fresh) noexcept;
    [[nodiscard]] double gain() const noexcept { return gain_; }
    void reset(double gain = 0.0) noexcept { gain_ = gain; }

  private:
    double step_;
    double gain_{0.0};
};

struct PortGuardConfig {
    double period_s{1e-3};
    double max_force_n{10.0};
    double max_force_rate_n_per_s{500.0};
    double fade_time_s{0.1};
    double max_passivity_damping{200.0};  // N s/m: at most this much damping is ever added
    bool passivity_enabled{true};
};

enum PortFlag : std::uint8_t {
    kPortOk = 0,
    kPortNonFiniteCommand = 1U << 0,   // renderer output was NaN/Inf: treated as stale
    kPortNonFinitePosition = 1U << 1,  // actuator reading was NaN/Inf: treated as stale
    kPortStale = 1U << 2,              // fading (input stale, invalid or not yet fresh)
    kPortForceSaturated = 1U << 3,
    kPortRateLimited = 1U << 4,
    kPortPassivityActive = 1U << 5,  // the passivity controller changed the force
};

struct PortCommand {
    double force_n{0.0};
    std::uint8_t flags{kPortOk};
};

[[nodiscard]] const char* describePortFlag(PortFlag flag) noexcept;

class ActuatorPortGuard {
  public:
    // Throws std::invalid_argument if a limit is not finite and positive.
    explicit ActuatorPortGuard(const PortGuardConfig& config);

    PortCommand apply(double u_desired, double ell, bool input_fresh) noexcept;

    [[nodiscard]] PassivityController& passivity() noexcept { return passivity_; }
    [[nodiscard]] const PassivityController& passivity() const noexcept { return passivity_; }
    [[nodiscard]] double fadeGain() const noexcept { return fade_.gain(); }

  private:
    PortGuardConfig config_;
    PassivityController passivity_;
    StaleInputFade fade_;
    double previous_force_n_{0.0};
    double held_force_n_{0.0};  // last valid force, faded out while the input is stale
};

}  // namespace haptic::kinesthetic
