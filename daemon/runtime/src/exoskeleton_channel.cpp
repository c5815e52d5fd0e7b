#include "haptic/runtime/exoskeleton_channel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "haptic/devices/actuator_limits.hpp"

namespace haptic::runtime {
namespace {

// Velocity from encoder differences is noisy (receive stamps jitter with the bus), so it is
// low-pass filtered; it only feeds the renderer's actuator damping.
constexpr double kVelocityFilter = 0.3;

kinesthetic::PortGuardConfig portGuardConfig(const config::DeviceConfig& device,
                                             const ChannelSettings& settings) {
    const auto& exo = device.exoskeleton();
    kinesthetic::PortGuardConfig guard;
    guard.period_s = settings.period_s;
    guard.max_force_n = std::min(device.safety.max_force_n, exo.actuator.max_force_n);
    guard.max_force_rate_n_per_s = device.safety.max_force_rate_n_per_s;
    guard.fade_time_s = static_cast<double>(device.safety.fade_out_ms) * 1e-3;
    guard.passivity_port_mass_kg = exo.rendering.passivity_port_mass_kg;
    return guard;
}

// How many of hapticd's latest commands a fresh state's echo may lag (alive counters, mod 16).
constexpr std::uint8_t kMaxEchoLagTicks = 4;

}  // namespace

kinesthetic::RenderParameters exoskeletonRenderParameters(const config::ExoskeletonConfig& exo) {
    kinesthetic::RenderParameters parameters;
    parameters.method = exo.rendering.method;
    parameters.tracking_stiffness = exo.rendering.tracking_stiffness_nm_per_rad;
    parameters.user_stiffness = exo.rendering.user_stiffness_nm_per_rad;
    parameters.actuator_damping = exo.rendering.actuator_damping_n_s_per_m;
    return parameters;
}

ExoskeletonChannel::ExoskeletonChannel(const config::DeviceConfig& device, can::CanBus& bus,
                                       const ChannelSettings& settings)
    : DriverChannel(device, bus, settings),
      model_(device.exoskeleton()),
      renderer_(model_, exoskeletonRenderParameters(device.exoskeleton())),
      guard_(portGuardConfig(device, settings)),
      max_constraints_(static_cast<std::size_t>(device.exoskeleton().rendering.max_constraints)),
      max_force_step_n_(device.safety.max_force_rate_n_per_s * settings.period_s),
      q_(kinesthetic::ConfigVector::Zero(model_.dofs())),
      q_dot_(kinesthetic::ConfigVector::Zero(model_.dofs())),
      tracking_stiffness_(device.exoskeleton().rendering.tracking_stiffness_nm_per_rad),
      max_stiffness_n_per_m_(device.safety.max_stiffness_n_per_m),
      max_velocity_m_per_s_(device.safety.max_velocity_m_per_s),
      lag_time_constant_s_(device.exoskeleton().actuator.lag_time_constant_s),
      force_tolerance_n_(device.exoskeleton().actuator.force_tolerance_n),
      actuator_(device.exoskeleton().actuator) {
    const auto& estimate = device.exoskeleton().rendering.user_stiffness_estimate;
    if (estimate.enabled) {
        kinesthetic::UserStiffnessEstimatorConfig config;
        config.period_s = settings.period_s;
        config.probe_frequency_hz = estimate.probe_frequency_hz;
        config.probe_time_s = estimate.probe_time_s;
        // A user is not 20 times softer or stiffer than the prior a lab configured.
        const double prior = device.exoskeleton().rendering.user_stiffness_nm_per_rad;
        config.min_stiffness = prior / 20.0;
        config.max_stiffness = prior * 20.0;
        estimator_.emplace(config);
        probe_amplitude_m_ = estimate.probe_amplitude_m;
        user_stiffness_target_ = prior;
    }
    applied_method_.assign(config::toString(device.exoskeleton().rendering.method));
    report_.kind = msgs::DeviceKind::kExoskeleton;
}

std::uint32_t ExoskeletonChannel::plausibilityFaults(std::int64_t now_ns) noexcept {
    const auto& state = driver_.state();
    const bool reports_enabled = (state.actuator.status & protocol::kExoEnabled) != 0;
    const bool reports_fault = (state.actuator.status & protocol::kExoFaulted) != 0;
    // The command of the last write(), as the device's first-order lag shapes it (a disabled
    // drive carries no current: zero at once).
    const double step = settings_.period_s / (lag_time_constant_s_ + settings_.period_s);
    expected_force_n_ =
        command_.enable ? expected_force_n_ + step * (command_.force_n - expected_force_n_) : 0.0;
    // Judged only on a fresh state (a silent device is the link monitor's to report).
    const bool judged = linkStateFresh() && state.actuator_updates > 0 && !reports_fault;
    // The time each contradiction has lasted on most frames; a fault once it outlasts the
    // heartbeat timeout (ContradictionTimer: one plausible frame does not restart it).
    auto lasting = [&](bool contradicts, ContradictionTimer& timer) -> double {
        if (!judged) {
            timer.reset();
            return 0.0;
        }
        return static_cast<double>(timer.update(contradicts, now_ns, heartbeatTimeoutNs())) * 1e-6;
    };
    if (const double ms = lasting(reports_enabled != command_.enable, enable_mismatch_); ms > 0.0) {
        std::snprintf(implausible_message_, sizeof(implausible_message_),
                      command_.enable ? "device reports disabled %.0f ms after enable"
                                      : "device reports enabled %.0f ms after disable",
                      ms);
        return kImplausibleFeedback;
    }
    // The device echoes the alive counter of the last command it accepted. Within the round
    // trip (a tick out, a device tick, a tick back) it is one of the last few hapticd sent;
    // otherwise the device obeys commands that are not hapticd's (another host on its id) or
    // none at all.
    const auto echo_lag = static_cast<std::uint8_t>(
        (driver_.lastCommandCounter() - state.actuator.command_echo) & 0x0F);
    if (const double ms = lasting(echo_lag > kMaxEchoLagTicks, echo_mismatch_); ms > 0.0) {
        std::snprintf(implausible_message_, sizeof(implausible_message_),
                      "device echoes command %u, hapticd sent %u: it obeys another host or none "
                      "for %.0f ms",
                      state.actuator.command_echo, driver_.lastCommandCounter(), ms);
        return kImplausibleFeedback;
    }
    // What the motor can deliver at the rod's speed (its torque-speed line), as the device does.
    const double deliverable_n =
        devices::deliverableForceN(expected_force_n_, rod_velocity_, actuator_);
    const double tolerance_n = force_tolerance_n_ + 0.2 * std::abs(deliverable_n);
    const bool force_off = command_.enable && reports_enabled &&
                           std::abs(state.actuator.force_n - deliverable_n) > tolerance_n;
    if (const double ms = lasting(force_off, force_mismatch_); ms > 0.0) {
        std::snprintf(implausible_message_, sizeof(implausible_message_),
                      "device measures %.2f N against %.2f N commanded for %.0f ms",
                      state.actuator.force_n, deliverable_n, ms);
        return kImplausibleFeedback;
    }
    return 0;
}

void ExoskeletonChannel::followMethod(const msgs::DeviceId& method) noexcept {
    if (method == applied_method_) {
        return;
    }
    // The state machine only accepts known names, so a miss cannot happen; keep the running
    // strategy if it ever did.
    if (const auto parsed = config::enumFromString<config::RenderingMethod>(method.view())) {
        renderer_.setMethod(*parsed);
        applied_method_ = method;
        if (estimator_) {
            estimator_->restart();  // a probe serves the method that uses k_u only
        }
        transition_ticks_left_ = kMethodTransitionTicks;
    }
}

void ExoskeletonChannel::measure() noexcept {
    const auto& state = driver_.state();
    stroke_m_ = state.actuator.stroke_m;
    if (state.encoder_updates == encoder_updates_) {
        return;
    }
    kinesthetic::ConfigVector q_new(q_.size());
    for (Eigen::Index i = 0; i < q_new.size(); ++i) {
        q_new[i] = state.encoders.joint_rad[static_cast<std::size_t>(i)];
    }
    if (encoder_updates_ > 0) {
        // Several frames can arrive in one read; never divide by less than half a period.
        const double dt_s =
            std::max(static_cast<double>(state.encoders_time_ns - encoder_time_ns_) * 1e-9,
                     0.5 * settings_.period_s);
        q_dot_ += kVelocityFilter * ((q_new - q_) / dt_s - q_dot_);
    }
    q_ = q_new;
    encoder_updates_ = state.encoder_updates;
    encoder_time_ns_ = state.encoders_time_ns;
}

void ExoskeletonChannel::compute(daemon::DaemonCore& core, std::size_t index,
                                 std::int64_t now_ns) noexcept {
    followMethod(core.stateMachine().method());
    const auto& state = driver_.state();
    const bool state_fresh =
        linkStateFresh() && state.encoder_updates > 0 && state.actuator_updates > 0;

    double desired_n = 0.0;
    std::uint8_t channel_flags = kinesthetic::kPortOk;
    const msgs::ConstraintSet* set = core.latestConstraintSet(index);
    if (state_fresh) {
        measure();
    }
    // B(q) once per tick: the environment's credit and the felt torque both use it.
    model_.actuationMatrix(q_, felt_actuation_);
    if (state_fresh) {
        std::span<const msgs::LinearConstraint> constraints;
        if (set != nullptr) {
            const auto used = set->constraints.used();
            constraints = used.first(std::min(used.size(), max_constraints_));
        }
        const double user_stiffness = estimateUserStiffness(state.actuator.force_n);
        // Between the sim's frames, a contact that moves is approached, not stepped to.
        renderAndCreditEnvironment(blend_.update(constraints), user_stiffness);
        desired_n = out_.actuator_force.size() > 0 ? out_.actuator_force[0] : 0.0;
        if (estimator_) {
            desired_n += probeForce();
        }
        // A method switch is bumpless: the new strategy's force moves from the strategy's force
        // of the tick before by at most the rate limit per tick. On the strategy's output only,
        // before the safety limits below: a render fault (its force 0) and the velocity fade
        // cut the force at once, switch or not (and anchoring to the faded force sent would
        // fade it twice).
        if (transition_ticks_left_ > 0 && out_.fault == kinesthetic::RenderFault::kNone &&
            !heldSafe() && core.outputGain(index) >= 1.0) {
            desired_n = std::clamp(desired_n, strategy_force_n_ - max_force_step_n_,
                                   strategy_force_n_ + max_force_step_n_);
        }
        strategy_force_n_ = desired_n;
        std::uint8_t limits = kinesthetic::kPortOk;
        if (renderer_.parameters().tracking_stiffness < tracking_stiffness_) {
            limits |= kinesthetic::kPortStiffnessLimited;
        }
        // Only a force that drives the rod along its motion fades: the runaway the limit
        // guards against. A force resisting a fast finger (a wall hit hard) stays, since
        // fading it would soften the wall and, released slowly, return more than it took.
        rod_velocity_ = felt_actuation_.col(0).dot(q_dot_);
        const double rod_speed = std::abs(rod_velocity_);
        if (rod_speed > max_velocity_m_per_s_ && desired_n * rod_velocity_ > 0.0) {
            desired_n *= std::max(0.0, 2.0 - rod_speed / max_velocity_m_per_s_);
            limits |= kinesthetic::kPortVelocityLimited;
        }
        channel_flags = limits;
    }
    // Without a fresh device state the guard fades the last good force out (never a step).
    // The output gain goes through the guard too, so that its rate limit and the passivity
    // controller see the force really sent (the gain rises during a fade-in, falls to 0 at
    // once on E-stop, FAULT or a dead sim).
    const double gain = heldSafe() ? 0.0 : core.outputGain(index);
    if (transition_ticks_left_ > 0) {
        --transition_ticks_left_;
    }
    const kinesthetic::PortCommand port = guard_.apply(desired_n, stroke_m_, state_fresh, gain);
    const double force_n = port.force_n;
    port_flags_ = static_cast<std::uint8_t>(port.flags | channel_flags);
    command_.force_n = force_n;
    command_.enable = gain > 0.0;
    if (estimator_) {
        // The share of the probe the guard let through (rate limit, passivity, fades, gain).
        probe_applied_n_ = desired_n != 0.0 && std::isfinite(force_n / desired_n)
                               ? probe_force_n_ * std::clamp(force_n / desired_n, 0.0, 1.0)
                               : 0.0;
        // The estimate reads the finger only while the probe really reaches it: in contact,
        // the port enabled at full gain, the probe at a quarter of its size or more, and only
        // for the method that uses k_u.
        probe_live_ = state_fresh && out_.in_contact && gain >= 1.0 && !heldSafe() &&
                      probe_scale_ >= kMinProbeScale &&
                      renderer_.parameters().method == config::RenderingMethod::kAnisotropic;
    }
    // A disabled port is disconnected from the virtual environment and stores nothing: the
    // next enable starts a new passivity interval. Without this, energy the observer booked
    // against a force the device never applied (it went limp on its own command timeout, a
    // fault, an E-stop) would block every later enable for the rest of the run.
    if (!command_.enable && force_n == 0.0) {
        guard_.passivity().reset();
        credit_stored_energy_ = true;
        probe_applied_n_ = 0.0;
    }

    fillLinkReport(core.state(), gain, now_ns);
    for (Eigen::Index i = 0; i < q_.size(); ++i) {
        const auto k = static_cast<std::size_t>(i);
        report_.joint_position_rad[k] = q_[i];
        report_.joint_velocity_rad_per_s[k] = q_dot_[i];
        report_.exoskeleton.joint_position_rad[k] = q_[i];
        report_.exoskeleton.proxy_position_rad[k] = out_.proxy.size() > i ? out_.proxy[i] : q_[i];
    }
    report_.actuator_position[0] = state.actuator.stroke_m;
    report_.actuator_force[0] = state.actuator.force_n;
    report_.exoskeleton.actuator_force_cmd_n = force_n;
    report_.exoskeleton.energy_observer_j = guard_.passivity().observedEnergy();
    report_.exoskeleton.environment_work_j = guard_.passivity().environmentWork();
    reportFeltAgainstReference(set, state.actuator.force_n);
}

double ExoskeletonChannel::probeForce() noexcept {
    // The probe is a known source, outside the rendering: the work its force did over the last
    // tick (the part of it the port guard let through) is credited to the passivity budget, so
    // that the controller judges the rendering alone (the probe's sine would otherwise spend
    // the budget the wall needs, and the wall would go soft). What the probe gave the finger is
    // kept in probe_energy_j_.
    const double probe_work_j = probe_applied_n_ * (stroke_m_ - probe_stroke_m_);
    if (probe_applied_n_ != 0.0 && std::isfinite(probe_work_j)) {
        guard_.passivity().creditEnvironmentWork(probe_work_j);
        probe_energy_j_ += probe_work_j;
    }
    probe_stroke_m_ = stroke_m_;
    // The proxy moved by the probe: its force through the coupling along the actuator. Both
    // tones together stay within kMaxProbeShare of the rendered force, so that the probe never
    // reverses the contact force (the wall would pull the finger in) and grows in with it at
    // contact onset.
    const double rendered_n = out_.actuator_force.size() > 0 ? out_.actuator_force[0] : 0.0;
    const double full_n = actuatorStiffness() * probe_amplitude_m_;
    probe_scale_ = full_n > 0.0 && std::isfinite(rendered_n)
                       ? std::min(1.0, kMaxProbeShare * std::abs(rendered_n) / (2.0 * full_n))
                       : 0.0;
    probe_force_n_ = out_.in_contact ? probe_scale_ * full_n * estimator_->probe() : 0.0;
    return probe_force_n_;
}

double ExoskeletonChannel::estimateUserStiffness(double felt_force_n) noexcept {
    const double current = renderer_.parameters().user_stiffness;
    if (!estimator_) {
        return current;
    }
    model_.actuatorCoordinates(q_, ell_);
    // Whether last tick's probe reached a finger in contact (probe_live_, set in compute()).
    estimator_->update(probe_live_, felt_force_n, ell_[0], felt_actuation_.col(0).squaredNorm());
    // The renderer keeps its k_u while the probe runs: a rendering that changed under it
    // would move the force by more than the probe does and spoil the window. The estimate
    // takes over when the probe ends (or the contact does, once an estimate was had).
    if (estimator_->valid()) {
        pending_user_stiffness_ = estimator_->stiffness();
    }
    if (!estimator_->probing() && std::isfinite(pending_user_stiffness_)) {
        user_stiffness_target_ = pending_user_stiffness_;
        pending_user_stiffness_ = std::numeric_limits<double>::quiet_NaN();
    }
    // The renderer's k_u follows the last estimate, also once the contact has ended.
    const double max_ratio = std::exp(kMaxUserStiffnessRate * settings_.period_s);
    return std::clamp(user_stiffness_target_, current / max_ratio, current * max_ratio);
}

void ExoskeletonChannel::renderAndCreditEnvironment(
    std::span<const msgs::LinearConstraint> constraints, double user_stiffness) noexcept {
    const bool stiffness_changes = user_stiffness != renderer_.parameters().user_stiffness;
    const bool moved =
        constraints.size() != rendered_constraints_.size() ||
        !std::equal(constraints.begin(), constraints.end(), rendered_constraints_.begin());
    // Along range(B) the coupling K acts as k_a for every method, so in actuator space it is
    // a spring of k_a / (B^T B) whose force is B^+ K (q_p - q) (damping is not part of it).
    // Where the linkage makes that stiffer than the device's maximum, k_a is lowered for this
    // tick so that it is not (before the solve: the subspace methods clamp their force).
    const double gram = felt_actuation_.col(0).squaredNorm();
    const double k_a = gram > 0.0 ? std::min(tracking_stiffness_, max_stiffness_n_per_m_ * gram)
                                  : tracking_stiffness_;
    (void)renderer_.setTrackingStiffness(k_a);
    const double stiffness = gram > 0.0 ? k_a / gram : 0.0;
    actuator_stiffness_ = stiffness;
    auto spring_force = [&](const kinesthetic::RenderOutput& out) {
        return out.fault == kinesthetic::RenderFault::kNone && gram > 0.0
                   ? felt_actuation_.col(0).dot(out.coupling_force) / gram
                   : std::numeric_limits<double>::quiet_NaN();
    };
    // No constraints: no spring force. A render that failed gives NaN, and no credit.
    double force_before_n = 0.0;
    if ((moved || stiffness_changes) && !rendered_constraints_.empty()) {
        renderer_.tick(q_, q_dot_, rendered_constraints_.used(), previous_environment_out_);
        force_before_n = spring_force(previous_environment_out_);
    }
    if (stiffness_changes) {
        (void)renderer_.setUserStiffness(user_stiffness);
    }
    renderer_.tick(q_, q_dot_, constraints, out_);
    if (credit_stored_energy_) {
        guard_.creditStoredEnergy(spring_force(out_), stiffness);
        credit_stored_energy_ = false;
    } else if (moved || stiffness_changes) {
        guard_.creditEnvironmentMotion(force_before_n, spring_force(out_), stiffness);
    }
    if (!moved) {
        return;
    }
    rendered_constraints_.clear();
    for (const auto& constraint : constraints) {
        rendered_constraints_.push_back(constraint);
    }
}

void ExoskeletonChannel::reportFeltAgainstReference(const msgs::ConstraintSet* set,
                                                    double felt_force_n) noexcept {
    auto& exo = report_.exoskeleton;
    exo.actuator_force_n = felt_force_n;
    exo.reference_torque_nm.fill(0.0);
    exo.ghost_torque_nm.fill(0.0);
    const auto n = static_cast<std::size_t>(q_.size());
    if (set != nullptr) {
        for (std::size_t i = 0; i < n; ++i) {
            exo.reference_torque_nm[i] = set->reference_torque_nm[i];
        }
    }
    double reference_squared = 0.0;
    double felt_along_reference = 0.0;
    double actuation_squared = 0.0;
    double actuation_along_reference = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double b = felt_actuation_(static_cast<Eigen::Index>(i), 0);
        actuation_squared += b * b;
        actuation_along_reference += b * exo.reference_torque_nm[i];
        const double felt = b * felt_force_n;
        exo.ghost_torque_nm[i] = felt;
        reference_squared += exo.reference_torque_nm[i] * exo.reference_torque_nm[i];
        felt_along_reference += felt * exo.reference_torque_nm[i];
    }
    // The one actuator's best share of the reference: B^+ tau_ref.
    exo.reference_actuator_force_n =
        actuation_squared > 0.0 ? actuation_along_reference / actuation_squared : 0.0;
    // With no reference at all, everything felt is ghost.
    if (reference_squared > 1e-18) {
        const double scale = felt_along_reference / reference_squared;
        for (std::size_t i = 0; i < n; ++i) {
            exo.ghost_torque_nm[i] -= scale * exo.reference_torque_nm[i];
        }
    }
}

}  // namespace haptic::runtime
