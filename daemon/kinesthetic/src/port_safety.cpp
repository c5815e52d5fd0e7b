#include "haptic/kinesthetic/port_safety.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace haptic::kinesthetic {

namespace {
// A spending force is budgeted for twice the last displacement (the motion may speed up).
constexpr double kPredictionMargin = 1.0;
// Kept in the reserve so that rounding in E (sums of ~1e-20 J products) cannot cross zero.
constexpr double kRoundingReserveJ = 1e-12;
}  // namespace

PassivityController::PassivityController(double period_s, double port_mass_kg) noexcept
    : period_s_(period_s), port_mass_kg_(port_mass_kg) {}

void PassivityController::reset() noexcept {
    energy_ = 0.0;
    environment_work_ = 0.0;
    velocity_ = 0.0;
    reversed_ = false;
    u_applied_ = 0.0;
    has_previous_ = false;
}

double PassivityController::observe(double ell) noexcept {
    if (!has_previous_) {
        ell_previous_ = ell;
        has_previous_ = true;
    }
    const double displacement = ell - ell_previous_;
    energy_ -= u_applied_ * displacement;
    reversed_ = displacement * velocity_ < 0.0;
    velocity_ = displacement / period_s_;
    ell_previous_ = ell;
    return velocity_;
}

void PassivityController::creditEnvironmentWork(double work_j) noexcept {
    if (std::isfinite(work_j)) {
        environment_work_ += work_j;
    }
}

double PassivityController::limit(double u_desired) const noexcept {
    if (!enabled_ || u_desired == 0.0) {
        return u_desired;
    }
    // Worst-case displacement along u over the next tick: the last one (grown by the margin
    // when u pushes along it, shrunk when u resists it) plus what u alone adds to a mass of
    // at least port_mass: d(|u|) = a + b |u|. Keep E - |u| d(|u|) >= 0.
    const double last = std::abs(velocity_) * period_s_;
    const bool spending = u_desired * velocity_ > 0.0 || reversed_;
    const double a =
        spending ? (1.0 + kPredictionMargin) * last : -last / (1.0 + kPredictionMargin);
    const double b = period_s_ * period_s_ / port_mass_kg_;
    const double magnitude = std::abs(u_desired);
    const double reserve = energy_ + environment_work_ - kRoundingReserveJ;
    // In deficit nothing may be spent: only a force too small to carry the port along itself
    // (d <= 0) passes, and it repays the deficit. Otherwise the largest |u| with
    // b u^2 + a u <= reserve.
    const double upper = reserve < 0.0 ? std::max(0.0, -a / b)
                                       : (-a + std::sqrt(a * a + 4.0 * b * reserve)) / (2.0 * b);
    return magnitude > upper ? std::copysign(upper, u_desired) : u_desired;
}

double saturateForce(double u, double previous, double max_force, double max_rate,
                     double period_s) noexcept {
    const double clamped = std::clamp(u, -max_force, max_force);
    const double step = max_rate * period_s;
    return std::clamp(clamped, std::min(previous, 0.0) - step, std::max(previous, 0.0) + step);
}

StaleInputFade::StaleInputFade(double period_s, double fade_time_s) noexcept
    : step_(fade_time_s > 0.0 ? period_s / fade_time_s : 1.0) {}

double StaleInputFade::update(bool input_fresh) noexcept {
    gain_ = std::clamp(gain_ + (input_fresh ? step_ : -step_), 0.0, 1.0);
    return gain_;
}

const char* describePortFlag(PortFlag flag) noexcept {
    switch (flag) {
        case kPortOk:
            return "ok";
        case kPortNonFiniteCommand:
            return "rendered force is NaN/Inf, fading out";
        case kPortNonFinitePosition:
            return "actuator position is NaN/Inf, fading out";
        case kPortStale:
            return "input stale, force fading";
        case kPortForceSaturated:
            return "force saturated";
        case kPortRateLimited:
            return "force rate limited";
        case kPortPassivityActive:
            return "passivity controller reduced the force";
        case kPortStiffnessLimited:
            return "coupling stiffness clamped to the device's maximum";
        case kPortVelocityLimited:
            return "actuator faster than its velocity limit, force fading";
    }
    return "unknown";
}

namespace {

bool positiveFinite(double value) {
    return value > 0.0 && std::isfinite(value);
}

}  // namespace

ActuatorPortGuard::ActuatorPortGuard(const PortGuardConfig& config)
    : config_(config),
      passivity_(config.period_s, config.passivity_port_mass_kg),
      fade_(config.period_s, config.fade_time_s) {
    if (!positiveFinite(config.period_s) || !positiveFinite(config.max_force_n) ||
        !positiveFinite(config.max_force_rate_n_per_s) || !positiveFinite(config.fade_time_s) ||
        !positiveFinite(config.passivity_port_mass_kg)) {
        throw std::invalid_argument(
            "ActuatorPortGuard: period, max force, max force rate, fade time and passivity port "
            "mass must be finite and > 0");
    }
    passivity_.setEnabled(config.passivity_enabled);
}

double ActuatorPortGuard::clampedSpringEnergy(double spring_force_n,
                                              double stiffness_n_per_m) const noexcept {
    const double magnitude = std::abs(spring_force_n);
    const double cap = config_.max_force_n;
    if (magnitude <= cap) {
        return magnitude * magnitude / (2.0 * stiffness_n_per_m);
    }
    return (cap * cap / 2.0 + cap * (magnitude - cap)) / stiffness_n_per_m;
}

void ActuatorPortGuard::creditEnvironmentMotion(double spring_force_before_n,
                                                double spring_force_after_n,
                                                double stiffness_n_per_m) noexcept {
    if (!std::isfinite(spring_force_before_n) || !std::isfinite(spring_force_after_n) ||
        !std::isfinite(stiffness_n_per_m) || !(stiffness_n_per_m > 0.0)) {
        return;
    }
    const double k = stiffness_n_per_m;
    double before = spring_force_before_n;
    if (before * spring_force_after_n < 0.0) {
        creditEnvironmentMotion(before, 0.0, k);
        before = 0.0;
    }
    const double after = spring_force_after_n;
    const double released = clampedSpringEnergy(before, k) - clampedSpringEnergy(after, k);
    if (released <= 0.0) {
        passivity_.creditEnvironmentWork(-released);
        return;
    }
    // The force the port held along the spring's force, over the far end's shift.
    const double held_along = std::copysign(1.0, before) * previous_force_n_;
    const double carried = std::max(0.0, held_along) * (std::abs(before) - std::abs(after)) / k;
    passivity_.creditEnvironmentWork(-std::min(released, carried));
}

PortCommand ActuatorPortGuard::apply(double u_desired, double ell, bool input_fresh,
                                     double output_gain) noexcept {
    PortCommand command;
    bool fresh = input_fresh;
    double u = u_desired;
    if (!std::isfinite(u)) {
        command.flags |= kPortNonFiniteCommand;
        fresh = false;
        u = 0.0;
    }
    const bool position_valid = std::isfinite(ell);
    if (!position_valid) {
        command.flags |= kPortNonFinitePosition;
        fresh = false;
    }
    // On invalid input keep pushing the last good force while fading it out, never a step.
    const double gain = fade_.update(fresh);
    if (!fresh || gain < 1.0) {
        command.flags |= kPortStale;
    }
    if (fresh) {
        held_force_n_ = std::clamp(u, -config_.max_force_n, config_.max_force_n);
    }
    // A NaN gain counts as 0: the port stops pushing rather than passing NaN on.
    const double output = output_gain > 0.0 ? std::min(output_gain, 1.0) : 0.0;
    const double target = held_force_n_ * gain * output;
    const double clamped = std::clamp(target, -config_.max_force_n, config_.max_force_n);
    if (fresh && std::abs(u) > config_.max_force_n) {
        command.flags |= kPortForceSaturated;
    }
    const double limited = saturateForce(clamped, previous_force_n_, config_.max_force_n,
                                         config_.max_force_rate_n_per_s, config_.period_s);
    if (limited != clamped) {
        command.flags |= kPortRateLimited;
    }
    // Passivity last: it only moves the force towards zero, so both limits above still hold
    // (a drop towards zero may be faster than the rate limit, the safe direction, as above).
    double applied = limited;
    if (position_valid) {
        passivity_.observe(ell);
        applied = passivity_.limit(limited);
        if (applied != limited) {
            command.flags |= kPortPassivityActive;
        }
    }
    command.force_n = applied;
    previous_force_n_ = applied;
    passivity_.record(applied);
    return command;
}

}  // namespace haptic::kinesthetic
