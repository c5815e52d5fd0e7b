#pragma once

// The exoskeleton's tick: encoders and stroke from the driver -> KinestheticRenderer (the
// strategy named by the daemon's current rendering method, fed the newest accepted
// ConstraintSet) -> ActuatorPortGuard (NaN, fade on stale device state, force clamp, rate
// limit, passivity) -> x DaemonCore::outputGain (sim fade, state machine; 0 while the device is
// held safe) -> force command. Enable is off whenever the gain is zero.
//
// The coupling (rendering.tracking_stiffness_nm_per_rad and the rest, assumed like the device
// geometry) is a spring of k_a / |B|^2 along the actuator, which the linkage makes stiffer as
// the finger flexes; k_a is lowered, tick by tick, so that this never exceeds
// safety.max_stiffness_n_per_m (the value the configuration's passivity margin was checked
// for). A force that drives the rod along its motion fades linearly from full at
// safety.max_velocity_m_per_s of rod speed to zero at twice that. The port guard then uses
// min(safety.max_force_n, actuator.max_force_n), safety.max_force_rate_n_per_s and
// safety.fade_out_ms.
//
// With rendering.user_stiffness_estimate enabled and the method anisotropic (the one that
// uses k_u), the proxy is moved by the probe (two sines of probe_amplitude_m along the
// actuator, added as k_a / |B|^2 times them to the force) while in contact with the port at
// full gain, and kinesthetic::UserStiffnessEstimator reads k_u off the finger's answer. The
// renderer's k_u follows the estimate at most by a factor e^(kMaxUserStiffnessRate dt) per
// tick, and each change is booked with the passivity controller like a moved wall: the spring
// force at the same q under the old k_u and the new. The probe itself is a known source
// outside the rendering: its work is credited to the passivity budget tick by tick (so the
// controller judges the rendering alone) and summed in probeEnergy(); it is bounded by the
// probe's amplitude and probe_time_s. Its peak is at most kMaxProbeShare of the rendered
// force, so it never reverses the contact force and grows in with it at contact onset.
//
// A method switch (allowed while RENDERING) is bumpless: for kMethodTransitionTicks after it,
// the new strategy's force may move from the force last sent by at most the rate limit per
// tick in either direction. (Otherwise the guard lets a force drop to zero at once, the safe
// direction; a switch must not make the finger feel a step either way.) That bound holds the
// strategy's output only: the safety limits after it (the velocity fade, a render fault's
// zero force, the guard's own fades and the output gain) still cut the force at once.

#include <cstdint>
#include <limits>
#include <optional>

#include "haptic/devices/exoskeleton_driver.hpp"
#include "haptic/kinesthetic/constraint_blend.hpp"
#include "haptic/kinesthetic/device_model.hpp"
#include "haptic/kinesthetic/port_safety.hpp"
#include "haptic/kinesthetic/renderer.hpp"
#include "haptic/kinesthetic/user_stiffness_estimator.hpp"
#include "haptic/runtime/contradiction_timer.hpp"
#include "haptic/runtime/device_channel.hpp"

namespace haptic::runtime {

// Joint-space rendering parameters for the shipped (assumed) exoskeleton.
[[nodiscard]] kinesthetic::RenderParameters exoskeletonRenderParameters(
    const config::ExoskeletonConfig& exo);

class ExoskeletonChannel final
    : public DriverChannel<devices::ExoskeletonDriver, protocol::ExoskeletonCommand> {
  public:
    // Throws std::invalid_argument when the device is not an exoskeleton or its parameters
    // are invalid.
    ExoskeletonChannel(const config::DeviceConfig& device, can::CanBus& bus,
                       const ChannelSettings& settings);

    void compute(daemon::DaemonCore& core, std::size_t index,
                 std::int64_t now_ns) noexcept override;

    [[nodiscard]] config::RenderingMethod method() const noexcept {
        return renderer_.parameters().method;
    }
    [[nodiscard]] const kinesthetic::RenderOutput& renderOutput() const noexcept { return out_; }
    [[nodiscard]] const kinesthetic::ActuatorPortGuard& portGuard() const noexcept {
        return guard_;
    }
    // What the port guard did to the last command (kinesthetic::PortFlag bits).
    [[nodiscard]] std::uint8_t portFlags() const noexcept { return port_flags_; }
    // The last render's coupling stiffness along the actuator, k_a / |B|^2 after the clamp
    // (N/m), and the rod velocity B^T q_dot the velocity limit judged (m/s).
    [[nodiscard]] double actuatorStiffness() const noexcept { return actuator_stiffness_; }
    [[nodiscard]] double rodVelocity() const noexcept { return rod_velocity_; }
    // The online estimate of k_u; nullptr unless rendering.user_stiffness_estimate is enabled.
    [[nodiscard]] const kinesthetic::UserStiffnessEstimator* userStiffnessEstimator()
        const noexcept {
        return estimator_ ? &*estimator_ : nullptr;
    }
    // Work the probe's force has done on the finger since start (J): energy the passivity
    // controller was told not to count against the rendering.
    [[nodiscard]] double probeEnergy() const noexcept { return probe_energy_j_; }
    // The k_u the renderer uses (the configured one until an estimate is valid).
    [[nodiscard]] double userStiffness() const noexcept {
        return renderer_.parameters().user_stiffness;
    }

  protected:
    // For longer than can.heartbeat_timeout_ms on a fresh state, the device reporting no fault
    // of its own: its enabled bit against the enable last commanded (a device that stays
    // enabled after a disable, or never enables), and, while enabled, the force it measures
    // against the commanded force through the actuator's lag.
    std::uint32_t plausibilityFaults(std::int64_t now_ns) noexcept override;
    [[nodiscard]] bool contradictionPending() const noexcept override {
        return enable_mismatch_.contradicting() || force_mismatch_.contradicting() ||
               echo_mismatch_.contradicting();
    }
    [[nodiscard]] const char* implausibleMessage() const noexcept override {
        return implausible_message_;
    }
    void commandSafe() noexcept override {
        command_.force_n = 0.0;
        command_.enable = false;
    }

    static constexpr int kMethodTransitionTicks = 200;
    // |d ln k_u / dt| of the renderer's k_u as it follows the estimate (1/s): rho* moves by at
    // most a factor 2 in 0.35 s.
    static constexpr double kMaxUserStiffnessRate = 2.0;
    // The probe's peak (both tones) as a share of the rendered force at most.
    static constexpr double kMaxProbeShare = 0.5;
    // Below this share of its full size the probe is too weak to read: no estimate.
    static constexpr double kMinProbeScale = 0.25;

  private:
    void followMethod(const msgs::DeviceId& method) noexcept;
    void measure() noexcept;
    // The estimator's tick and the k_u the renderer is to use next (rate-limited).
    [[nodiscard]] double estimateUserStiffness(double felt_force_n) noexcept;
    // The probe's force for this tick; books the last tick's probe work (see the .cpp).
    [[nodiscard]] double probeForce() noexcept;
    // Telemetry's yardstick: the sim's fully actuated reference torque, and the felt torque
    // B(q) F of the force the actuator reports, split into its part along the reference and
    // the rest, the ghost torque (docs/hapticd.md, "Reference and ghost torque").
    void reportFeltAgainstReference(const msgs::ConstraintSet* set, double felt_force_n) noexcept;
    // Renders `constraints` at the current q; when they differ from those of the last render,
    // credits the port's passivity budget with the work the sim's moving objects did on the
    // coupling (ActuatorPortGuard::creditEnvironmentMotion): the spring force under the old
    // constraints and under the new, both at this q, so the port's own motion is not counted
    // twice. The first render of a passivity interval credits what the spring holds.
    // A change of k_u (user_stiffness) is credited the same way.
    void renderAndCreditEnvironment(std::span<const msgs::LinearConstraint> constraints,
                                    double user_stiffness) noexcept;

    kinesthetic::ExoskeletonDevice model_;  // before renderer_, which keeps a reference
    kinesthetic::KinestheticRenderer renderer_;
    kinesthetic::ActuatorPortGuard guard_;
    std::size_t max_constraints_;
    msgs::DeviceId applied_method_{};
    int transition_ticks_left_{0};
    double strategy_force_n_{0.0};  // the strategy's force (with the probe) of the last fresh tick
    double max_force_step_n_{0.0};  // the rate limit over one period
    kinesthetic::ConfigVector q_;
    kinesthetic::ConfigVector q_dot_;
    double stroke_m_{0.0};
    std::uint64_t encoder_updates_{0};
    std::int64_t encoder_time_ns_{0};
    kinesthetic::RenderOutput out_;
    kinesthetic::ConstraintBlend blend_;
    // The constraints of the last render, and scratch for re-rendering them at a new q.
    msgs::BoundedArray<msgs::LinearConstraint, msgs::kMaxConstraints> rendered_constraints_{};
    kinesthetic::RenderOutput previous_environment_out_;
    bool credit_stored_energy_{true};  // the passivity interval (re)starts at the next render
    std::uint8_t port_flags_{kinesthetic::kPortOk};
    kinesthetic::ActuationMatrix felt_actuation_;  // B(q) for the felt joint torque
    double tracking_stiffness_;  // k_a as configured; the renderer's is lowered by the clamp
    double max_stiffness_n_per_m_;
    double max_velocity_m_per_s_;
    double actuator_stiffness_{0.0};
    double rod_velocity_{0.0};
    std::optional<kinesthetic::UserStiffnessEstimator> estimator_;
    double probe_amplitude_m_{0.0};
    double probe_force_n_{0.0};          // the probe's part of the last desired force
    double probe_applied_n_{0.0};        // the share of it the guard let through
    double probe_scale_{0.0};            // of the full probe, by kMaxProbeShare
    bool probe_live_{false};             // the last probe reached a finger in contact
    double user_stiffness_target_{0.0};  // the last estimate (the prior before any)
    double pending_user_stiffness_{std::numeric_limits<double>::quiet_NaN()};  // while probing
    double probe_stroke_m_{0.0};       // the stroke that force was applied from
    double probe_energy_j_{0.0};       // what the probe's force gave the finger, in all
    kinesthetic::ActuatorVector ell_;  // sigma(q), scratch
    ContradictionTimer enable_mismatch_;
    // The commanded force through the actuator's first-order lag: what the device should
    // measure. Compared with what it does (actuator.force_tolerance_n + 20 %).
    double lag_time_constant_s_;
    double force_tolerance_n_;
    config::ActuatorConfig actuator_;
    double expected_force_n_{0.0};
    ContradictionTimer force_mismatch_;
    ContradictionTimer echo_mismatch_;
    char implausible_message_[msgs::kShortTextCapacity]{};
};

}  // namespace haptic::runtime
