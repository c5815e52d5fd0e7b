#pragma once

// Health of one device link: heartbeat and state freshness, the device's own fault reports,
// the last transmit and the bus state. Times are CLOCK_MONOTONIC ns passed in by the caller,
// so the loop decides what "now" is and tests drive it without waiting.

#include <cstdint>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/protocol/frame_codec.hpp"

namespace haptic::devices {

// Why a device link is not usable; a bit set. Zero means healthy.
enum LinkFault : std::uint32_t {
    kNoHeartbeatYet = 1U << 0,  // nothing heard since start (or since a reset)
    kHeartbeatLost = 1U << 1,   // last heartbeat older than heartbeat_timeout_ms
    kStateStale = 1U << 2,      // last complete state older than state_timeout_ms
    kDeviceFault = 1U << 3,     // the device reports a fault (fault frame or heartbeat mode)
    kBusOff = 1U << 4,          // the CAN controller is bus-off
    kTransmitFailed = 1U << 5,  // the last command could not be queued (back-pressure, error)
    // The device restarted: a heartbeat's uptime went back. Reported once per restart (it is
    // an event; the daemon latches it), by the faults() call after the heartbeat.
    kDeviceRebooted = 1U << 6,
};

[[nodiscard]] const char* linkFaultName(LinkFault fault) noexcept;

// Bound on the frames one poll() handles, so a flooded bus cannot stretch a tick.
inline constexpr int kMaxFramesPerPoll = 64;

// Reads and hands at most kMaxFramesPerPoll pending frames to `handle_frame(frame, now_ns)`,
// which returns true for frames of its device; returns how many were.
template <typename HandleFrame>
int pollFrames(can::CanBus& bus, std::int64_t now_ns, HandleFrame&& handle_frame) noexcept {
    int handled = 0;
    can::CanFrame frame;
    for (int i = 0; i < kMaxFramesPerPoll; ++i) {
        if (bus.read(frame) != can::IoResult::kOk) {
            break;
        }
        if (handle_frame(frame, now_ns)) {
            ++handled;
        }
    }
    return handled;
}

class LinkMonitor {
  public:
    explicit LinkMonitor(const config::CanConfig& can) noexcept;

    // A heartbeat in fault mode, or naming an active fault, marks the device faulted.
    void onHeartbeat(const protocol::Heartbeat& heartbeat, std::int64_t now_ns) noexcept;
    void onState(std::int64_t now_ns) noexcept;
    void onFaultReport(const protocol::FaultReport& fault) noexcept {
        device_fault_ = fault.active;
        fault_since_poll_ = fault_since_poll_ || fault.active;
        if (fault.active) {
            last_fault_code_ = static_cast<std::uint8_t>(fault.code);
        }
    }
    // The code of the last active fault the device reported (fault frame or heartbeat), 0 if
    // none yet: what a fault seen and gone within one poll was.
    [[nodiscard]] std::uint8_t lastFaultCode() const noexcept { return last_fault_code_; }
    void onTransmit(can::IoResult result) noexcept {
        transmit_failed_ = result != can::IoResult::kOk;
    }

    // Re-evaluates the timeouts; returns the timeout bits (kNoHeartbeatYet, kHeartbeatLost,
    // kStateStale). A newly raised bit is counted once per occurrence.
    std::uint32_t evaluate(std::int64_t now_ns) noexcept;
    // All LinkFault bits: the timeouts plus device fault, bus-off and transmit failure.
    std::uint32_t faults(std::int64_t now_ns, can::BusState bus_state) noexcept;

    [[nodiscard]] std::uint64_t heartbeatLossCount() const noexcept { return heartbeat_losses_; }
    [[nodiscard]] std::uint64_t staleCount() const noexcept { return stale_events_; }
    [[nodiscard]] std::int64_t lastHeartbeatNs() const noexcept { return last_heartbeat_ns_; }
    [[nodiscard]] std::int64_t lastStateNs() const noexcept { return last_state_ns_; }
    [[nodiscard]] std::uint64_t rebootCount() const noexcept { return reboots_; }
    // The uptimes of the last restart: the one before it, and the first one after (ms).
    [[nodiscard]] std::uint32_t uptimeBeforeRebootMs() const noexcept { return uptime_before_ms_; }
    [[nodiscard]] std::uint32_t uptimeAfterRebootMs() const noexcept { return uptime_after_ms_; }

  private:
    std::int64_t heartbeat_timeout_ns_;
    std::int64_t state_timeout_ns_;
    bool heartbeat_seen_{false};
    bool state_seen_{false};
    std::int64_t last_heartbeat_ns_{0};
    std::int64_t last_state_ns_{0};
    std::uint32_t previous_{kNoHeartbeatYet};
    bool device_fault_{false};
    // A fault seen since the last faults(): a fault frame followed in the same poll by a
    // heartbeat without one is still reported once.
    bool fault_since_poll_{false};
    std::uint8_t last_fault_code_{0};
    bool transmit_failed_{false};
    std::uint64_t heartbeat_losses_{0};
    std::uint64_t stale_events_{0};
    std::uint32_t last_uptime_ms_{0};
    std::uint64_t reboots_{0};
    std::uint64_t reboots_reported_{0};
    std::uint32_t uptime_before_ms_{0};
    std::uint32_t uptime_after_ms_{0};
};

}  // namespace haptic::devices
