#pragma once

// Safety stage for one actuator port, applied after the renderer every 1 kHz tick
// (docs/algorithms.md §5.7.3, §6.9), in this order: NaN/Inf rejection, fade to zero on stale input,
// force and force-rate saturation, then the time-domain passivity observer/controller
// (Hannaford-Ryu) last, so that it observes the force that is really applied.
// Everything is noexcept, allocation- and lock-free, O(1).

#include <cstdint>
#include <limits>

namespace haptic::kinesthetic {

// Energy bookkeeping of the port, sign convention of §5.7.3: u acts along increasing ell. The
// force applied at tick k is held over [k, k+1] (zero-order hold), so the energy absorbed by
// the rendered environment is E_{k+1} = E_k - u_k (ell_{k+1} - ell_k): exactly the work the
// actuator does, booked one tick late. E < 0 means the rendering has given the user net energy.
//
// The controller is the conservative (reduce-only) variant of Hannaford-Ryu for an impedance
// port: it only ever scales the force towards zero, never adds a damping term and never flips
// the sign, so it cannot overshoot and cannot inject energy itself. It keeps E_{k+1} >= 0 by
// bounding the next displacement along u by d(|u|) = a + b |u|: a is the last displacement,
// times (1 + margin) if u pushes along it (or it just reversed), divided by it if u resists;
// b |u| = T^2 |u| / m is how far u alone carries a mass of at least m within the tick (a
// resisting force can itself reverse a slow motion; a spending one speeds it up). The force is
// capped so that |u| d(|u|) <= E_k. The guarantee holds as long as the port moves at least
// `port_mass` and the other forces (the user) change the displacement by less than the margin
// per tick. In deficit only forces with d <= 0 (they can only earn) pass.
//
// A virtual environment that moves is a source: when the sim moves an object into a finger
// that holds still (the hand translating into a wall), the port does no work, yet the coupling
// must push. The budget is therefore E_k plus the work the environment's own motion did on the
// coupling, credited by the caller (creditEnvironmentWork; ActuatorPortGuard computes it). It
// is signed, so a wall that jitters in and out credits nothing on balance, and one that
// retreats takes back what its approach gave. Passivity then holds for the port and the
// environment's motion together: the device never gives the finger more than the port
// absorbed plus what the moving objects put in.
// It must be the last stage before the actuator (after force and rate saturation), and
// record() must get the force actually applied: a limiter after it could hold a force the
// controller wanted gone. The cost is the classic one of passivity control: a wall that has
// not stored energy yet (first contact, fast reversals) pushes back less for a few ms.
class PassivityController {
  public:
    // port_mass_kg: a lower bound on the mass the actuator moves (its reflected inertia; the
    // hand only adds to it), so that the controller can bound how far its own force carries
    // the port within one tick.
    PassivityController(double period_s, double port_mass_kg) noexcept;

    // Start of a tick: the measured actuator coordinate. Returns the velocity estimate.
    double observe(double ell) noexcept;
    // The force reduced towards zero as far as passivity requires (the input when disabled).
    [[nodiscard]] double limit(double u_desired) const noexcept;
    // End of a tick: the force actually applied.
    void record(double u_applied) noexcept { u_applied_ = u_applied; }
    // Work (J, signed) the virtual environment's own motion did on the coupling since the
    // last call; non-finite values are ignored.
    void creditEnvironmentWork(double work_j) noexcept;

    void setEnabled(bool enabled) noexcept { enabled_ = enabled; }
    [[nodiscard]] bool enabled() const noexcept { return enabled_; }
    void reset() noexcept;

    // Energy absorbed at the port so far (J); its negative is what the device delivered.
    [[nodiscard]] double observedEnergy() const noexcept { return energy_; }
    // The environment's own work credited so far (J).
    [[nodiscard]] double environmentWork() const noexcept { return environment_work_; }

  private:
    double period_s_;
    double port_mass_kg_;
    double energy_{0.0};
    double environment_work_{0.0};
    double ell_previous_{0.0};
    double velocity_{0.0};
    bool reversed_{false};  // the last displacement reversed the one before
    double u_applied_{0.0};
    bool has_previous_{false};
    bool enabled_{true};
};

// Clamp to [-max_force, max_force], then limit how fast the force grows: from `previous` it may
// fall to any value between `previous` and zero at once (releasing the hand is the safe
// direction: E-stop, FAULT and a dead sim cut the force immediately) but grow away from zero,
// on either side, by at most max_rate * period per tick. A sign flip therefore drops to zero
// and rises on the other side at the rate limit.
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
    double passivity_port_mass_kg{0.1};  // lower bound on the moved mass, see PassivityController
    bool passivity_enabled{true};
};

enum PortFlag : std::uint8_t {
    kPortOk = 0,
    kPortNonFiniteCommand = 1U << 0,   // renderer output was NaN/Inf: treated as stale
    kPortNonFinitePosition = 1U << 1,  // actuator reading was NaN/Inf: treated as stale
    kPortStale = 1U << 2,              // fading (input stale, invalid or not yet fresh)
    kPortForceSaturated = 1U << 3,
    kPortRateLimited = 1U << 4,
    kPortPassivityActive = 1U << 5,  // the passivity controller reduced the force
    // Set by the device's channel, before the guard:
    kPortStiffnessLimited = 1U << 6,  // the coupling along the actuator clamped to max stiffness
    kPortVelocityLimited = 1U << 7,   // the actuator moved faster than its limit: force faded
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

    // output_gain in [0, 1] scales the force before the rate limit: the daemon's fade-in after
    // a sim stall or an enable, and 0 while the port is not allowed to push. Because the limit
    // applies to the product, a gain that rises together with the rendered force can never
    // make the force sent step faster than max_force_rate_n_per_s.
    PortCommand apply(double u_desired, double ell, bool input_fresh,
                      double output_gain = 1.0) noexcept;

    // The environment's side of the passivity budget. Seen from the actuator, the coupling is
    // a spring of stiffness k (N/m) whose far end the environment moves: its force
    // u = k (ell_p - ell) is the renderer's spring force (damping excluded). When the sim moves
    // its objects at a fixed ell, from spring force u_before to u_after:
    //   loading (|u| grows): the credit is psi(u_after) - psi(u_before), the work that loads
    //     the spring, where psi is the energy of the spring cut off at max_force_n (beyond the
    //     clamp the port feels max_force_n): u^2 / 2k up to the clamp, then linear;
    //   unloading (|u| shrinks): the debit is that energy drop, but at most the force the port
    //     held times the far end's shift: a port that the rate limit, a fade or this controller
    //     kept below the spring never received the spring's energy, so it cannot owe it.
    // A sign change unloads to zero, then loads. So a wall that jitters about a loaded state
    // credits nothing on balance once the port carries the spring's force, and at most lets
    // the port catch up with the spring before. Non-finite input or k <= 0: no credit.
    void creditEnvironmentMotion(double spring_force_before_n, double spring_force_after_n,
                                 double stiffness_n_per_m) noexcept;
    // A new passivity interval (after reset, e.g. the port was disabled) starts with what the
    // spring holds: passivity allows a system to give back its initial storage, and the finger
    // may have entered the wall while the port was off.
    void creditStoredEnergy(double spring_force_n, double stiffness_n_per_m) noexcept {
        creditEnvironmentMotion(0.0, spring_force_n, stiffness_n_per_m);
    }
    // psi above.
    [[nodiscard]] double clampedSpringEnergy(double spring_force_n,
                                             double stiffness_n_per_m) const noexcept;

    [[nodiscard]] PassivityController& passivity() noexcept { return passivity_; }
    [[nodiscard]] const PassivityController& passivity() const noexcept { return passivity_; }
    [[nodiscard]] double fadeGain() const noexcept { return fade_.gain(); }
    [[nodiscard]] const PortGuardConfig& config() const noexcept { return config_; }

  private:
    PortGuardConfig config_;
    PassivityController passivity_;
    StaleInputFade fade_;
    double previous_force_n_{0.0};  // the force applied last tick, after the output gain
    double held_force_n_{0.0};      // last valid force, faded out while the input is stale
};

}  // namespace haptic::kinesthetic
