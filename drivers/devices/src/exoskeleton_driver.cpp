#include "haptic/devices/exoskeleton_driver.hpp"

namespace haptic::devices {

using protocol::ExoskeletonMessage;

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
            link_.onHeartbeat(message.heartbeat, now_ns);
            return true;
        case ExoskeletonMessage::Type::kFault:
            state_.last_fault = message.fault;
            link_.onFaultReport(message.fault);
            return true;
    }
    // The state is complete once both halves have arrived; its age is that of the older.
    if (state_.actuator_updates > 0 && state_.encoder_updates > 0) {
        link_.onState(state_.actuator_time_ns < state_.encoders_time_ns ? state_.actuator_time_ns
                                                                        : state_.encoders_time_ns);
    }
    return true;
}

}  // namespace haptic::devices
