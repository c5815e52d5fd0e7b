#include "haptic/devices/thimble_driver.hpp"

namespace haptic::devices {

using protocol::ThimbleMessage;

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

}  // namespace haptic::devices
