#include "haptic/devices/estop_relay_monitor.hpp"

namespace haptic::devices {

bool EstopRelayMonitor::handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
    if (frame.id != decoder_.id()) {
        return false;
    }
    protocol::EstopButton button = protocol::EstopButton::kPressed;
    if (decoder_.decode(frame, button)) {
        button_ = button;
        // A press is held until evaluate() has reported it: a press and a release read in the
        // same poll (a loop late by a relay period) must still stop the devices.
        pressed_since_evaluate_ =
            pressed_since_evaluate_ || button == protocol::EstopButton::kPressed;
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
        pressed_since_evaluate_ = false;  // silence is reported, and stops the devices itself
        return EstopInput::kSilent;
    }
    if (last_status_ns_ < 0) {
        return EstopInput::kAwaitingFirstStatus;  // hapticd may start before the relay
    }
    const bool pressed = button_ == protocol::EstopButton::kPressed || pressed_since_evaluate_;
    pressed_since_evaluate_ = false;
    return pressed ? EstopInput::kPressed : EstopInput::kReleased;
}

}  // namespace haptic::devices
