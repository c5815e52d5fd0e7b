#include "haptic/devices/estop_relay_monitor.hpp"

namespace haptic::devices {

bool EstopRelayMonitor::handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
    if (frame.id != decoder_.id()) {
        return false;
    }
    protocol::EstopButton button = protocol::EstopButton::kPressed;
    if (decoder_.decode(frame, button)) {
        button_ = button;
        last_status_ns_ = now_ns;
    }
    return true;
}

EstopInput EstopRelayMonitor::evaluate(std::int64_t now_ns) noexcept {
    if (first_evaluate_ns_ < 0) {
        first_evaluate_ns_ = now_ns;
    }
    const std::int64_t heard_ns = last_status_ns_ >= 0 ? last_status_ns_ : first_evaluate_ns_;
    if (now_ns - heard_ns > timeout_ns_) {
        return EstopInput::kSilent;
    }
    if (last_status_ns_ < 0) {
        return EstopInput::kAwaitingFirstStatus;  // hapticd may start before the relay
    }
    return button_ == protocol::EstopButton::kPressed ? EstopInput::kPressed
                                                      : EstopInput::kReleased;
}

}  // namespace haptic::devices
