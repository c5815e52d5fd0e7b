#include "haptic/emu/device_emulator.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "haptic/emu/device_models.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {

void DeviceEmulator::tick(std::int64_t now_ns) noexcept {
    bool first_tick = false;
    if (faults_.takeReboot()) {
        // What a power cycle leaves: a device that has heard no command and holds nothing.
        started_ = false;
        command_seen_ = false;
        timed_out_ = false;
        awaiting_safe_command_ = re_arms_only_on_a_safe_command_;
        onReboot();
    }
    if (!started_) {
        started_ = true;
        first_tick = true;
        start_ns_ = now_ns;
        next_heartbeat_ns_ = now_ns;
        next_tick_ns_ = now_ns + options_.tick_ns;
    }
    if (faults_.takeFaultChange()) {
        protocol::FaultReport report;
        report.active = faults_.deviceFault() != 0;
        report.code = static_cast<protocol::DeviceFaultCode>(
            report.active ? faults_.deviceFault() : static_cast<std::uint8_t>(1));
        can::CanFrame frame;
        codec_base_.encodeFault(report, frame);
        send(frame, now_ns);
        if (!report.active) {
            awaiting_safe_command_ = re_arms_only_on_a_safe_command_;
        }
    }
    checkCommandTimeout(now_ns);
    if (now_ns >= next_heartbeat_ns_) {
        next_heartbeat_ns_ += options_.heartbeat_period_ns;
        if (next_heartbeat_ns_ <= now_ns) {
            next_heartbeat_ns_ = now_ns + options_.heartbeat_period_ns;
        }
        if (!faults_.heartbeatStopped()) {
            protocol::Heartbeat heartbeat;
            heartbeat.active_fault = activeFault();
            heartbeat.mode = heartbeat.active_fault != 0 ? protocol::DeviceMode::kFault
                                                         : protocol::DeviceMode::kOperational;
            heartbeat.uptime_ms = static_cast<std::uint32_t>((now_ns - start_ns_) / 1'000'000);
            can::CanFrame frame;
            codec_base_.encodeHeartbeat(heartbeat, frame);
            send(frame, now_ns);
        }
    }
    if (options_.mode == EmulatorMode::kStream) {
        // Bounded catch-up: after a long stall the model jumps rather than spinning.
        bool stepped = first_tick;  // the device reports its state once at start, too
        for (int i = 0; i < 10 && now_ns >= next_tick_ns_; ++i) {
            next_tick_ns_ += options_.tick_ns;
            stepModel(tickSeconds());
            stepped = true;
        }
        if (now_ns >= next_tick_ns_) {
            next_tick_ns_ = now_ns + options_.tick_ns;
        }
        // State once per model tick, as the device does: tick() also runs whenever a frame
        // wakes the emulator's loop, which must not multiply the state rate.
        if (stepped && !faults_.stateStopped()) {
            sendState(now_ns);
        }
    }
    faults_.flush(bus_, now_ns);
}

std::uint8_t DeviceEmulator::activeFault() const noexcept {
    if (faults_.deviceFault() != 0) {
        return faults_.deviceFault();
    }
    return timed_out_ ? static_cast<std::uint8_t>(protocol::DeviceFaultCode::kCommandTimeout) : 0;
}

void DeviceEmulator::checkCommandTimeout(std::int64_t now_ns) noexcept {
    // Lockstep time is the command count: a command cannot arrive late there.
    if (options_.mode == EmulatorMode::kLockstep || !command_seen_ || timed_out_ ||
        now_ns - last_command_ns_ <= command_timeout_ns_) {
        return;
    }
    timed_out_ = true;
    ++timeouts_;
    reportCommandTimeout(true, now_ns);
}

void DeviceEmulator::reportCommandTimeout(bool active, std::int64_t now_ns) noexcept {
    protocol::FaultReport report;
    report.code = protocol::DeviceFaultCode::kCommandTimeout;
    report.active = active;
    report.detail = static_cast<std::uint32_t>(command_timeout_ns_ / 1'000'000);
    can::CanFrame frame;
    codec_base_.encodeFault(report, frame);
    send(frame, now_ns);
}

bool DeviceEmulator::onCommandAccepted(std::int64_t now_ns, bool asks_safe) noexcept {
    ++commands_;
    command_seen_ = true;
    last_command_ns_ = now_ns;
    if (timed_out_ && asks_safe) {
        timed_out_ = false;
        reportCommandTimeout(false, now_ns);
    }
    if (awaiting_safe_command_ && asks_safe && faults_.deviceFault() == 0) {
        awaiting_safe_command_ = false;
    }
    const bool apply = !holdsSafe();
    if (options_.mode == EmulatorMode::kLockstep) {
        stepModel(tickSeconds());
        sendState(now_ns);
        faults_.flush(bus_, now_ns);
    }
    return apply;
}

namespace {

// Base-from-member: listed before DeviceEmulator, so the codec exists when that base binds it.
template <typename Codec>
struct CodecOwner {
    explicit CodecOwner(const config::DeviceConfig& device) : codec_(device) {}
    Codec codec_;
};

class ExoskeletonEmulator final : private CodecOwner<protocol::ExoskeletonCodec>,
                                  public DeviceEmulator {
  public:
    ExoskeletonEmulator(const config::DeviceConfig& device, can::CanBus& bus,
                        EmulatorOptions options)
        // A force device: after a restart or a fault it obeys no enable still in flight.
        : CodecOwner(device),
          DeviceEmulator(bus, options, codec_, device, ReArm::kOnlyOnASafeCommand),
          model_(device) {}

    void handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept override {
        const protocol::ExoskeletonMessage message = codec_.decode(frame);
        if (message.type != protocol::ExoskeletonMessage::Type::kCommand) {
            return;
        }
        last_command_counter_ = message.counter;
        // Set before the lockstep tick inside onCommandAccepted(), undone if it refuses.
        const protocol::ExoskeletonCommand previous = command_;
        command_ = message.command;
        if (faults().stuckEnable() && previous.enable) {
            command_.enable = true;
        }
        if (!onCommandAccepted(now_ns, !message.command.enable)) {
            command_ = previous;
        }
    }
    [[nodiscard]] ExoskeletonModel* exoskeletonModel() noexcept override { return &model_; }

  private:
    void stepModel(double dt_s) noexcept override {
        model_.step(dt_s, command_.force_n * faults_.forceFraction(),
                    command_.enable && activeFault() == 0 && !holdsSafe());
    }
    void onReboot() noexcept override {
        command_ = protocol::ExoskeletonCommand{};
        model_.disable();
    }
    void sendState(std::int64_t now_ns) noexcept override {
        protocol::ExoskeletonActuatorState actuator;
        actuator.stroke_m = model_.strokeM();
        actuator.force_n = model_.forceN();
        actuator.status =
            static_cast<std::uint8_t>((model_.enabled() ? protocol::kExoEnabled : 0) |
                                      (activeFault() != 0 ? protocol::kExoFaulted : 0) |
                                      (model_.atStrokeMin() ? protocol::kExoAtStrokeMin : 0) |
                                      (model_.atStrokeMax() ? protocol::kExoAtStrokeMax : 0));
        actuator.command_echo = static_cast<std::uint8_t>(
            (last_command_counter_ + faults_.echoOffset()) % protocol::kCounterModulo);
        can::CanFrame frame;
        if (codec_.encodeActuatorState(actuator, frame)) {
            send(frame, now_ns);
        }
        protocol::ExoskeletonEncoders encoders;
        encoders.joint_rad = model_.jointRad();
        if (codec_.encodeEncoders(encoders, frame)) {
            send(frame, now_ns);
        }
    }

    ExoskeletonModel model_;
    protocol::ExoskeletonCommand command_;
    std::uint8_t last_command_counter_{0};
};

class ThimbleEmulator final : private CodecOwner<protocol::ThimbleCodec>, public DeviceEmulator {
  public:
    ThimbleEmulator(const config::DeviceConfig& device, can::CanBus& bus, EmulatorOptions options)
        : CodecOwner(device),
          // A position device: its servos follow their setpoints, the retract path hapticd
          // commands while it holds a fault among them.
          DeviceEmulator(bus, options, codec_, device, ReArm::kOnAnyCommand),
          model_(device),
          retract_rad_(retractAngles(device)) {
        target_.servo_target_rad = model_.angleRad();
    }

    void handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept override {
        const protocol::ThimbleMessage message = codec_.decode(frame);
        if (message.type != protocol::ThimbleMessage::Type::kCommand) {
            return;
        }
        bool asks_retract = true;
        for (std::size_t i = 0; i < 3; ++i) {
            asks_retract = asks_retract && std::abs(message.command.servo_target_rad[i] -
                                                    retract_rad_[i]) <= kRetractToleranceRad;
        }
        const protocol::ThimbleCommand previous = target_;
        target_ = message.command;
        if (!onCommandAccepted(now_ns, asks_retract)) {
            target_ = previous;
        }
    }
    [[nodiscard]] const ThimbleModel* thimbleModel() const noexcept override { return &model_; }

  private:
    // The firmware's home pose: the plate at its retract pose (the same kinematics hapticd
    // uses, from the same device file), where a timed-out device drives its servos.
    static std::array<double, 3> retractAngles(const config::DeviceConfig& device) {
        const tactile::ThimbleKinematics kinematics(device.thimble());
        const auto ik = kinematics.inverse(kinematics.retractPose());
        if (!ik.ok()) {
            throw std::invalid_argument("thimble '" + device.name +
                                        "': the retract pose has no inverse kinematics");
        }
        return {ik.servo_rad[0], ik.servo_rad[1], ik.servo_rad[2]};
    }

    void stepModel(double dt_s) noexcept override {
        // An injected fault freezes the servos where they are; the command timeout retracts.
        if (faults_.deviceFault() == 0) {
            std::array<double, 3> target = holdsSafe() ? retract_rad_ : target_.servo_target_rad;
            if (const std::uint8_t stuck = faults_.stuckServo(); stuck >= 1 && stuck <= 3) {
                target[stuck - 1U] = std::numeric_limits<double>::quiet_NaN();  // holds
            }
            model_.step(dt_s, target);
        }
    }
    // The firmware starts at home: the retract pose.
    void onReboot() noexcept override { target_.servo_target_rad = retract_rad_; }
    void sendState(std::int64_t now_ns) noexcept override {
        protocol::ThimbleState state;
        state.servo_angle_rad = model_.angleRad();
        can::CanFrame frame;
        if (codec_.encodeState(state, frame)) {
            send(frame, now_ns);
        }
    }

    // Commands quantise angles to 1e-4 rad; a retract command lands within half of that.
    static constexpr double kRetractToleranceRad = 1e-3;

    ThimbleModel model_;
    std::array<double, 3> retract_rad_;
    protocol::ThimbleCommand target_;
};

}  // namespace

std::unique_ptr<DeviceEmulator> makeEmulator(const config::DeviceConfig& device, can::CanBus& bus,
                                             EmulatorOptions options) {
    if (device.isExoskeleton()) {
        return std::make_unique<ExoskeletonEmulator>(device, bus, options);
    }
    return std::make_unique<ThimbleEmulator>(device, bus, options);
}

}  // namespace haptic::emu
