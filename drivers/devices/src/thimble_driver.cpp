#include "haptic/devices/thimble_driver.hpp"

namespace haptic::devices {

using protocol::ThimbleMessage;

ThimbleDriver::ThimbleDriver(const config::DeviceConfig& device, can::CanBus& bus)
    : bus_(bus), codec_(device), link_(device.can) {}

int ThimbleDriver::poll(std::int64_t now_ns) noexcept {
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

bool ThimbleDriver::handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
    const ThimbleMessage message = codec_.decode(frame);
    switch (message.type) {
        case ThimbleMessage::Type::kNotForThisDevice:
            return false;
        case ThimbleMessage::Type::kRejected:
        case ThimbleMessage::Type::kCommand:
            break;
        case ThimbleMessage::Type::kState:
            state_.servos = message.state;
            state_.state_time_ns = now_ns;
            ++state_.state_updates;
            link_.onState(now_ns);
            break;
        case ThimbleMessage::Type::kHeartbeat:
            state_.heartbeat = message.heartbeat;
            link_.onHeartbeat(now_ns);
            device_fault_ = message.heartbeat.mode == protocol::DeviceMode::kFault ||
                            message.heartbeat.active_fault != 0;
            break;
        case ThimbleMessage::Type::kFault:
            state_.last_fault = message.fault;
            device_fault_ = message.fault.active;
            break;
    }
    return true;
}

can::IoResult ThimbleDriver::sendCommand(const protocol::ThimbleCommand& command) noexcept {
    can::CanFrame frame;
    if (!codec_.encodeCommand(command, frame)) {
        return can::IoResult::kInvalid;
    }
    const can::IoResult result = bus_.write(frame);
    transmit_failed_ = result != can::IoResult::kOk;
    return result;
}

std::uint32_t ThimbleDriver::faults(std::int64_t now_ns) noexcept {
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
