#include "haptic/devices/exoskeleton_driver.hpp"

namespace haptic::devices {

using protocol::ExoskeletonMessage;

ExoskeletonDriver::ExoskeletonDriver(const config::DeviceConfig& device, can::CanBus& bus)
    : bus_(bus), codec_(device), link_(device.can) {}

int ExoskeletonDriver::poll(std::int64_t now_ns) noexcept {
    int handled = 0;
    can::CanFrame frame;
    for (int i = 0; i < kMaxFramesPerPoll; ++i) {
        if (bus_.read(frame) != can::IoResult::kOk) {
            break;
        }
        if (handleFrame(frame, now_ns)) {
            ++handled;
        }
    }
    return handled;
}

bool ExoskeletonDriver::handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
    const ExoskeletonMessage message = codec_.decode(frame);
    switch (message.type) {
        case ExoskeletonMessage::Type::kNotForThisDevice:
            return false;
        case ExoskeletonMessage::Type::kRejected:
        case ExoskeletonMessage::Type::kCommand:  // our own id echoed back: not a state
            return true;
        case ExoskeletonMessage::Type::kActuatorState:
            state_.actuator = message.actuator;
            state_.actuator_time_ns = now_ns;
            ++state_.actuator_updates;
            break;
        case ExoskeletonMessage::Type::kEncoders:
            state_.encoders = message.encoders;
            state_.encoders_time_ns = now_ns;
            ++state_.encoder_updates;
            break;
        case ExoskeletonMessage::Type::kHeartbeat:
            state_.heartbeat = message.heartbeat;
            link_.onHeartbeat(now_ns);
            device_fault_ = message.heartbeat.mode == protocol::DeviceMode::kFault ||
                            message.heartbeat.active_fault != 0;
            return true;
        case ExoskeletonMessage::Type::kFault:
            state_.last_fault = message.fault;
            device_fault_ = message.fault.active;
            return true;
    }
    // The state is complete once both halves have arrived; its age is that of the older.
    if (state_.actuator_updates > 0 && state_.encoder_updates > 0) {
        link_.onState(state_.actuator_time_ns < state_.encoders_time_ns ? state_.actuator_time_ns
                                                                        : state_.encoders_time_ns);
    }
    return true;
}

can::IoResult ExoskeletonDriver::sendCommand(const protocol::ExoskeletonCommand& command) noexcept {
    const std::uint8_t counter = codec_.peekCounter(protocol::FrameRole::kCommand);
    can::CanFrame frame;
    if (!codec_.encodeCommand(command, frame)) {
        return can::IoResult::kInvalid;
    }
    const can::IoResult result = bus_.write(frame);
    transmit_failed_ = result != can::IoResult::kOk;
    if (result == can::IoResult::kOk) {
        last_counter_ = counter;
    }
    return result;
}

std::uint32_t ExoskeletonDriver::faults(std::int64_t now_ns) noexcept {
    std::uint32_t faults = link_.evaluate(now_ns);
    if (device_fault_) {
        faults |= kDeviceFault;
    }
    if (bus_.state() == can::BusState::kBusOff) {
        faults |= kBusOff;
    }
    if (transmit_failed_) {
        faults |= kTransmitFailed;
    }
    return faults;
}

}  // namespace haptic::devices
