#include "haptic/devices/link_monitor.hpp"

namespace haptic::devices {
namespace {

// Clock drift and frame delays between the device's uptime and the host's clock.
constexpr double kUptimeSlackMs = 1000.0;

}  // namespace

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
        case kDeviceRebooted:
            return "device rebooted";
    }
    return "unknown";
}

LinkMonitor::LinkMonitor(const config::CanConfig& can) noexcept
    : heartbeat_timeout_ns_(static_cast<std::int64_t>(can.heartbeat_timeout_ms) * 1'000'000),
      state_timeout_ns_(static_cast<std::int64_t>(can.state_timeout_ms) * 1'000'000) {}

void LinkMonitor::onHeartbeat(const protocol::Heartbeat& heartbeat, std::int64_t now_ns) noexcept {
    // Uptime grows with the host's clock while the device runs. Its advance, modulo 2^32 (a
    // u32 of ms wraps after 49 days), is judged against the host time since the last
    // heartbeat: a restart makes it go back, i.e. look like nearly 2^32 ms.
    const std::uint32_t advance_ms = heartbeat.uptime_ms - last_uptime_ms_;
    const double elapsed_ms = static_cast<double>(now_ns - last_heartbeat_ns_) * 1e-6;
    if (heartbeat_seen_ && static_cast<double>(advance_ms) > 1.1 * elapsed_ms + kUptimeSlackMs) {
        ++reboots_;
        uptime_before_ms_ = last_uptime_ms_;
        uptime_after_ms_ = heartbeat.uptime_ms;
    }
    last_uptime_ms_ = heartbeat.uptime_ms;
    heartbeat_seen_ = true;
    last_heartbeat_ns_ = now_ns;
    device_fault_ = heartbeat.mode == protocol::DeviceMode::kFault || heartbeat.active_fault != 0;
    fault_since_poll_ = fault_since_poll_ || device_fault_;
    if (heartbeat.active_fault != 0) {
        last_fault_code_ = heartbeat.active_fault;
    }
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
    if (device_fault_ || fault_since_poll_) {
        faults |= kDeviceFault;
    }
    fault_since_poll_ = false;
    if (bus_state == can::BusState::kBusOff) {
        faults |= kBusOff;
    }
    if (transmit_failed_) {
        faults |= kTransmitFailed;
    }
    if (reboots_ != reboots_reported_) {
        reboots_reported_ = reboots_;
        faults |= kDeviceRebooted;
    }
    return faults;
}

}  // namespace haptic::devices
