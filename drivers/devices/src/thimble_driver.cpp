#include "haptic/devices/thimble_driver.hpp"

namespace haptic::devices {

using protocol::ThimbleMessage;

ThimbleDriver::ThimbleDriver(const config::DeviceConfig& device, can::CanBus& bus)
    : bus_(bus), codec_(device), link_(device.can) {}

int ThimbleDriver::poll(std::int64_t now_ns) noexcept {
    return pollFrames(bus_, now_ns, [this](const can::CanFrame& frame, std::int64_t now) {
        return handleFrame(frame, now);
    });
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
            link_.onHeartbeat(message.heartbeat, now_ns);
            break;
        case ThimbleMessage::Type::kFault:
            state_.last_fault = message.fault;
            link_.onFaultReport(message.fault);
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
    link_.onTransmit(result);
    return result;
}

std::uint32_t ThimbleDriver::faults(std::int64_t now_ns) noexcept {
    return link_.faults(now_ns, bus_.state());
}

}  // namespace haptic::devices
