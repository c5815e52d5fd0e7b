#include "haptic/runtime/thimble_channel.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace haptic::runtime {
namespace {

tactile::ServoAngles retractAngles(const tactile::ThimbleKinematics& kinematics) {
    const auto ik = kinematics.inverse(kinematics.retractPose());
    if (!ik.ok()) {
        throw std::invalid_argument("thimble: the retract pose has no inverse kinematics (" +
                                    std::string(tactile::toString(ik.error)) + ")");
    }
    return ik.servo_rad;
}

}  // namespace

ThimbleChannel::ThimbleChannel(const config::DeviceConfig& device, can::CanBus& bus,
                               const ChannelSettings& settings)
    : DriverChannel(device, bus, settings),
      kinematics_(device.thimble()),
      optimiser_(kinematics_, tactile::OptimiserSettings::fromConfig(device.thimble())),
      retract_servo_rad_(retractAngles(kinematics_)),
      pad_limiter_(tactile::PadSafetySettings::fromConfig(device, settings.period_s)),
      limiter_(device.thimble().servos, retract_servo_rad_) {
    solved_.dofs = kinematics_.retractPose();
    solved_.servo_rad = retract_servo_rad_;
    report_.kind = msgs::DeviceKind::kThimble;
    measured_dofs_ = kinematics_.retractPose();
    sent_dofs_ = kinematics_.retractPose();
    // The rate and speed limits start from the retract pose the servo limiter starts at.
    tactile::PlatformPose retract_pose;
    if (kinematics_.platformPose(sent_dofs_, retract_pose) == tactile::KinematicsError::kNone) {
        (void)pad_limiter_.commanded(retract_pose, nullptr);
    }
    command_.servo_target_rad = retract_servo_rad_;
    const auto& servos = device.thimble().servos;
    servo_lag_s_ = servos.lag_time_constant_s;
    servo_max_rate_rad_per_s_ = servos.max_rate_rad_per_s;
    angle_tolerance_rad_ = servos.angle_tolerance_rad;
}

std::uint32_t ThimbleChannel::plausibilityFaults(std::int64_t now_ns) noexcept {
    const auto& state = driver_.state();
    const auto& measured = state.servos.servo_angle_rad;
    // Judged only on a fresh state of a device reporting no fault of its own (a silent or
    // faulted device is the link monitor's to report; one retracting on its own command
    // timeout goes where it wants).
    const bool judged = linkStateFresh() && state.state_updates > 0 && deviceFaultCode() == 0;
    if (!judged || !expected_synced_) {
        expected_servo_rad_ = measured;
        expected_synced_ = judged;
        expected_at_ns_ = now_ns;
        angle_mismatch_.reset();
        return 0;
    }
    // Over the time that really passed: after a stall of hapticd the servos have moved on.
    const double dt_s = std::clamp(static_cast<double>(now_ns - expected_at_ns_) * 1e-9, 0.0, 0.1);
    expected_at_ns_ = now_ns;
    const double step = dt_s / (servo_lag_s_ + dt_s);
    const double max_step_rad = servo_max_rate_rad_per_s_ * dt_s;
    std::size_t worst = 0;
    double worst_error = 0.0;
    for (std::size_t k = 0; k < expected_servo_rad_.size(); ++k) {
        const double move = step * (command_.servo_target_rad[k] - expected_servo_rad_[k]);
        expected_servo_rad_[k] += std::clamp(move, -max_step_rad, max_step_rad);
        const double error = std::abs(measured[k] - expected_servo_rad_[k]);
        if (error > worst_error) {
            worst_error = error;
            worst = k;
        }
    }
    // Lasting on most frames, not restarted by one plausible frame (ContradictionTimer).
    const std::int64_t lasted_ns =
        angle_mismatch_.update(worst_error > angle_tolerance_rad_, now_ns, heartbeatTimeoutNs());
    if (lasted_ns == 0) {
        return 0;
    }
    constexpr double kDeg = 180.0 / 3.14159265358979323846;
    std::snprintf(implausible_message_, sizeof(implausible_message_),
                  "servo %zu at %.1f deg against %.1f deg expected for %.0f ms", worst + 1,
                  measured[worst] * kDeg, expected_servo_rad_[worst] * kDeg,
                  static_cast<double>(lasted_ns) * 1e-6);
    return kImplausibleFeedback;
}

void ThimbleChannel::measure() noexcept {
    const auto& state = driver_.state();
    if (state.state_updates == state_updates_) {
        return;
    }
    state_updates_ = state.state_updates;
    // Newton from the last estimate: 1-3 iterations between consecutive 1 kHz frames.
    const tactile::ForwardResult fk =
        kinematics_.forward(state.servos.servo_angle_rad, measured_dofs_);
    if (fk.ok()) {
        measured_dofs_ = fk.dofs;
        measured_pose_ = fk.pose;
    }
}

tactile::PlatformDofs ThimbleChannel::blendDofs(double gain) const noexcept {
    const tactile::PlatformDofs& retract = kinematics_.retractPose();
    tactile::PlatformDofs target;
    target.height_m = retract.height_m + gain * (solved_.dofs.height_m - retract.height_m);
    target.tilt_x_rad = retract.tilt_x_rad + gain * (solved_.dofs.tilt_x_rad - retract.tilt_x_rad);
    target.tilt_y_rad = retract.tilt_y_rad + gain * (solved_.dofs.tilt_y_rad - retract.tilt_y_rad);
    return target;
}

tactile::ServoAngles ThimbleChannel::blend(double gain) const noexcept {
    const tactile::InverseResult ik =
        kinematics_.inverse(blendDofs(gain), /*check_workspace=*/false);
    if (ik.ok()) {
        return ik.servo_rad;
    }
    tactile::ServoAngles angles{};
    for (std::size_t i = 0; i < angles.size(); ++i) {
        angles[i] = retract_servo_rad_[i] + gain * (solved_.servo_rad[i] - retract_servo_rad_[i]);
    }
    return angles;
}

void ThimbleChannel::compute(daemon::DaemonCore& core, std::size_t index,
                             std::int64_t now_ns) noexcept {
    const auto& state = driver_.state();
    const bool state_fresh = linkStateFresh() && state.state_updates > 0;
    if (state_fresh) {
        measure();
    }
    const std::uint64_t accepted = core.acceptedCount(index);
    const msgs::ContactSurface* surface = core.latestContactSurface(index);
    // A device held safe (offline, faulted) is sent the retract pose whatever the surface:
    // solve the newest surface once it can be used, not before.
    if (surface != nullptr && accepted != solved_from_ && !heldSafe()) {
        solved_ = optimiser_.solve(*surface);
        solved_from_ = accepted;
    }

    // A stale device state cannot be trusted to be where we think: retract as well.
    const double gain = heldSafe() || !state_fresh ? 0.0 : core.outputGain(index);
    // The safety limits judge the pose against the newest pad the sim sent, whether or not
    // the optimiser could use it.
    pad_limit_ = pad_limiter_.limit(gain, surface, [this](double g, tactile::PlatformPose& pose) {
        return kinematics_.platformPose(blendDofs(g), pose) == tactile::KinematicsError::kNone;
    });
    const tactile::ServoAngles previous_sent = limiter_.last();
    tactile::LimitedServoCommand limited =
        limiter_.step(blend(pad_limit_.gain), settings_.period_s);
    // The servo limiter moves each servo on its own, and blend() falls back to blending the
    // angles where a pose has no inverse kinematics: the pose sent need not be the one judged.
    // Judge it too: shorten the whole servo step by one factor until it keeps the limits, and
    // never send angles whose pose cannot be judged.
    const tactile::PadSafetyLimiter::ServoStep sent = pad_limiter_.judgeStep(
        previous_sent, limited.servo_rad, surface, /*retracting=*/pad_limit_.gain <= 0.0,
        [this](const tactile::ServoAngles& angles, tactile::ForwardResult& result) {
            result = kinematics_.forward(angles, sent_dofs_);
        });
    if (sent.shortened) {
        limited.servo_rad = sent.servo_rad;
        limiter_.holdAt(sent.servo_rad);
        pad_limit_.flags |= static_cast<std::uint8_t>(tactile::PadFlag::kServoStep);
    }
    command_.servo_target_rad = limited.servo_rad;
    if (sent.forward.ok()) {
        sent_dofs_ = sent.forward.dofs;
        pad_limit_.pad_force_n = pad_limiter_.commanded(sent.forward.pose, surface);
    }

    fillLinkReport(core.state(), gain, now_ns);
    for (std::size_t i = 0; i < 3; ++i) {
        report_.joint_position_rad[i] = state.servos.servo_angle_rad[i];
        report_.actuator_position[i] = state.servos.servo_angle_rad[i];
        report_.thimble.servo_angle_rad[i] = state.servos.servo_angle_rad[i];
        report_.thimble.servo_angle_cmd_rad[i] = limited.servo_rad[i];
    }
    report_.thimble.platform_height_m = solved_.dofs.height_m;
    report_.thimble.platform_tilt_x_rad = solved_.dofs.tilt_x_rad;
    report_.thimble.platform_tilt_y_rad = solved_.dofs.tilt_y_rad;
    report_.thimble.pad_force_model_n = pad_limit_.pad_force_n;
    report_.thimble.pad_limit_flags = pad_limit_.flags;
    if (surface != nullptr) {
        report_.thimble.reference_force_device_n = surface->reference_force_device_n;
        report_.thimble.reference_moment_device_nm = surface->reference_moment_device_nm;
    }
    for (int i = 0; i < 3; ++i) {
        report_.platform_position_m[static_cast<std::size_t>(i)] = measured_pose_.position_m[i];
    }
    const Eigen::Quaterniond orientation(measured_pose_.rotation);
    report_.platform_orientation_wxyz = {orientation.w(), orientation.x(), orientation.y(),
                                         orientation.z()};
}

}  // namespace haptic::runtime
