#include "haptic/kinesthetic/port_safety.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace haptic::kinesthetic {

namespace {
constexpr double kPredictionMargin = 1.0;
}  // namespace

PassivityController::PassivityController(double period_s, double max_damping,
                                         double max_force_rate) noexcept
    : period_s_(period_s), max_damping_(max_damping), max_rate_(max_force_rate) {}

void PassivityController::reset() noexcept {
    energy_ = 0.0;
    velocity_ = 0.0;
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
    velocity_ = displacement / period_s_;
    ell_previous_ = ell;
    return velocity_;
}

double PassivityController::correct(double u_desired) const noexcept {
    const double v = velocity_;
    if (!enabled_ || v == 0.0) {
        return u_desired;
    }
    const double speed = std::abs(v);
    const double ramp = std::isfinite(max_rate_) ? 0.5 * speed / max_rate_ : 0.0;  // * u^2
    // A force pushing along the motion spends the reserve E; a force resisting it refills E
    // but may push along the motion after the next reversal, when it can only ramp down at the
    // rate limit (costing about |v| u^2 / (2 rate)). Cap |u| so that the reserve, after the
    // next period (budgeted at (1 + margin) times the last displacement when spending), still
    // pays for that ramp.
    const auto cap = [&](double u) {
        double allowed = std::numeric_limits<double>::infinity();
        if (u * v > 0.0) {
            const double spend = (1.0 + kPredictionMargin) * speed * period_s_;  // * |u|
            if (energy_ <= 0.0) {
                allowed = 0.0;
            } else if (ramp > 0.0) {
                allowed = (-spend + std::sqrt(spend * spend + 4.0 * ramp * energy_)) / (2.0 * ramp);
            } else {
                allowed = energy_ / spend;
            }
        } else if (ramp > 0.0) {
            const double gain = speed * period_s_;  // * |u|
            const double discriminant = gain * gain + 4.0 * ramp * energy_;
            allowed = discriminant > 0.0 ? (gain + std::sqrt(discriminant)) / (2.0 * ramp)
                                         : gain / (2.0 * ramp);
        }
        return std::abs(u) > allowed ? std::copysign(allowed, u) : u;
    };
    double u = cap(u_desired);
    // Whatever deficit remains is damped out, b = -(E - u v T) / (T v^2) up to its cap; the
    // damped force resists the motion, and is capped like any other.
    const double predicted = energy_ - u * v * period_s_;
    if (predicted < 0.0) {
        const double damping = std::min(-predicted / (period_s_ * v * v), max_damping_);
        u = cap(u - damping * v);
    }
    return u;
}

double saturateForce(double u, double previous, double max_force, double max_rate,
                     double period_s) noexcept {
    const double clamped = std::clamp(u, -max_force, max_force);
    const double step = max_rate * period_s;
    return std::clamp(clamped, previous - step, previous + step);
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
            return "passivity controller adding damping";
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
      passivity_(config.period_s, config.max_passivity_damping, config.max_force_rate_n_per_s),
      fade_(config.period_s, config.fade_time_s) {
    if (!positiveFinite(config.period_s) || !positiveFinite(config.max_force_n) ||
        !positiveFinite(config.max_force_rate_n_per_s) || !positiveFinite(config.fade_time_s) ||
        !(config.max_passivity_damping >= 0.0) || !std::isfinite(config.max_passivity_damping)) {
        throw std::invalid_argument(
            "ActuatorPortGuard: period, max force, max force rate and fade time must be finite "
            "and > 0, max passivity damping finite and >= 0");
    }
    passivity_.setEnabled(config.passivity_enabled);
}

PortCommand ActuatorPortGuard::apply(double u_desired, double ell, bool input_fresh) noexcept {
    PortCommand command;
    bool fresh = input_fresh;
    double u = u_desired;
    if (!std::isfinite(u)) {
        command.flags |= kPortNonFiniteCommand;
        fresh = false;
        u = 0.0;
    }
    if (std::isfinite(ell)) {
        passivity_.observe(ell);
        const double corrected = passivity_.correct(u);
        if (corrected != u) {
            command.flags |= kPortPassivityActive;
        }
        u = corrected;
    } else {
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
    const double target = held_force_n_ * gain;
    const double clamped = std::clamp(target, -config_.max_force_n, config_.max_force_n);
    if (fresh && std::abs(u) > config_.max_force_n) {
        command.flags |= kPortForceSaturated;
    }
    const double limited = saturateForce(clamped, previous_force_n_, config_.max_force_n,
                                         config_.max_force_rate_n_per_s, config_.period_s);
    if (limited != clamped) {
        command.flags |= kPortRateLimited;
    }
    command.force_n = limited;
    previous_force_n_ = limited;
    passivity_.record(limited);
    return command;
}

}  // namespace haptic::kinesthetic
