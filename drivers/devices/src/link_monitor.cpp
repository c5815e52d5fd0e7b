#include "haptic/devices/link_monitor.hpp"

namespace haptic::devices {

const char* linkFaultName(LinkFault fault) noexcept {
    switch (fault) {
        case kNoHeartbeatYet:
            return "no heartbeat yet";
        case kHeartbeatLost:
            return "heartbeat lost";
        case kStateStale:
            return "state stale";
        case kDeviceFault:
            return "device fault";
        case kBusOff:
            return "bus-off";
        case kTransmitFailed:
            return "transmit failed";
    }
    return "unknown";
}

LinkMonitor::LinkMonitor(const config::CanConfig& can) noexcept
    : heartbeat_timeout_ns_(static_cast<std::int64_t>(can.heartbeat_timeout_ms) * 1'000'000),
      state_timeout_ns_(static_cast<std::int64_t>(can.state_timeout_ms) * 1'000'000) {}

void LinkMonitor::onHeartbeat(const protocol::Heartbeat& heartbeat, std::int64_t now_ns) noexcept {
    heartbeat_seen_ = true;
    last_heartbeat_ns_ = now_ns;
    device_fault_ = heartbeat.mode == protocol::DeviceMode::kFault || heartbeat.active_fault != 0;
}

void LinkMonitor::onState(std::int64_t now_ns) noexcept {
    state_seen_ = true;
    last_state_ns_ = now_ns;
}

std::uint32_t LinkMonitor::evaluate(std::int64_t now_ns) noexcept {
    std::uint32_t faults = 0;
    if (!heartbeat_seen_) {
        faults |= kNoHeartbeatYet;
    } else if (now_ns - last_heartbeat_ns_ > heartbeat_timeout_ns_) {
        faults |= kHeartbeatLost;
    }
    if (!state_seen_ || now_ns - last_state_ns_ > state_timeout_ns_) {
        faults |= kStateStale;
    }
    const std::uint32_t raised = faults & ~previous_;
    if ((raised & kHeartbeatLost) != 0) {
        ++heartbeat_losses_;
    }
    if ((raised & kStateStale) != 0 && state_seen_) {
        ++stale_events_;
    }
    previous_ = faults;
    return faults;
}

std::uint32_t LinkMonitor::faults(std::int64_t now_ns, can::BusState bus_state) noexcept {
    std::uint32_t faults = evaluate(now_ns);
    if (device_fault_) {
        faults |= kDeviceFault;
    }
    if (bus_state == can::BusState::kBusOff) {
        faults |= kBusOff;
    }
    if (transmit_failed_) {
        faults |= kTransmitFailed;
    }
    return faults;
}

}  // namespace haptic::devices
