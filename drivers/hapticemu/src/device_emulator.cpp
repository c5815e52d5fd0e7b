#include "haptic/emu/device_emulator.hpp"

#include "haptic/emu/device_models.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace haptic::emu {

void DeviceEmulator::tick(std::int64_t now_ns) noexcept {
    bool first_tick = false;
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
    }
    if (now_ns >= next_heartbeat_ns_) {
        next_heartbeat_ns_ += options_.heartbeat_period_ns;
        if (next_heartbeat_ns_ <= now_ns) {
            next_heartbeat_ns_ = now_ns + options_.heartbeat_period_ns;
        }
        if (!faults_.heartbeatStopped()) {
            protocol::Heartbeat heartbeat;
            heartbeat.active_fault = faults_.deviceFault();
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
        if (stepped) {
            sendState(now_ns);
        }
    }
    faults_.flush(bus_, now_ns);
}

void DeviceEmulator::onCommandAccepted(std::int64_t now_ns) noexcept {
    ++commands_;
    if (options_.mode == EmulatorMode::kLockstep) {
        stepModel(tickSeconds());
        sendState(now_ns);
        faults_.flush(bus_, now_ns);
    }
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
        : CodecOwner(device), DeviceEmulator(bus, options, codec_), model_(device) {}

    void handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept override {
        const protocol::ExoskeletonMessage message = codec_.decode(frame);
        if (message.type != protocol::ExoskeletonMessage::Type::kCommand) {
            return;
        }
        command_ = message.command;
        last_command_counter_ = message.counter;
        onCommandAccepted(now_ns);
    }
    [[nodiscard]] ExoskeletonModel* exoskeletonModel() noexcept override { return &model_; }

  private:
    void stepModel(double dt_s) noexcept override {
        model_.step(dt_s, command_.force_n, command_.enable && faults_.deviceFault() == 0);
    }
    void sendState(std::int64_t now_ns) noexcept override {
        protocol::ExoskeletonActuatorState actuator;
        actuator.stroke_m = model_.strokeM();
        actuator.force_n = model_.forceN();
        actuator.status =
            static_cast<std::uint8_t>((model_.enabled() ? protocol::kExoEnabled : 0) |
                                      (faults_.deviceFault() != 0 ? protocol::kExoFaulted : 0) |
                                      (model_.atStrokeMin() ? protocol::kExoAtStrokeMin : 0) |
                                      (model_.atStrokeMax() ? protocol::kExoAtStrokeMax : 0));
        actuator.command_echo = last_command_counter_;
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
        : CodecOwner(device), DeviceEmulator(bus, options, codec_), model_(device) {
        target_.servo_target_rad = model_.angleRad();
    }

    void handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept override {
        const protocol::ThimbleMessage message = codec_.decode(frame);
        if (message.type != protocol::ThimbleMessage::Type::kCommand) {
            return;
        }
        target_ = message.command;
        onCommandAccepted(now_ns);
    }
    [[nodiscard]] const ThimbleModel* thimbleModel() const noexcept override { return &model_; }

  private:
    void stepModel(double dt_s) noexcept override {
        if (faults_.deviceFault() == 0) {
            model_.step(dt_s, target_.servo_target_rad);
        }
    }
    void sendState(std::int64_t now_ns) noexcept override {
        protocol::ThimbleState state;
        state.servo_angle_rad = model_.angleRad();
        can::CanFrame frame;
        if (codec_.encodeState(state, frame)) {
            send(frame, now_ns);
        }
    }

    ThimbleModel model_;
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
