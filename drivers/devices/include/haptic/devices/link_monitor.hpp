#pragma once

// Heartbeat and state freshness for one device link. Times are CLOCK_MONOTONIC ns passed in
// by the caller, so the loop decides what "now" is and tests drive it without waiting.

#include <cstdint>

#include "haptic/config/device.hpp"

namespace haptic::devices {

// Why a device link is not usable; a bit set. Zero means healthy.
enum LinkFault : std::uint32_t {
    kNoHeartbeatYet = 1U << 0,  // nothing heard since start (or since a reset)
    kHeartbeatLost = 1U << 1,   // last heartbeat older than heartbeat_timeout_ms
    kStateStale = 1U << 2,      // last complete state older than state_timeout_ms
    kDeviceFault = 1U << 3,     // the device reports a fault (fault frame or heartbeat mode)
    kBusOff = 1U << 4,          // the CAN controller is bus-off
    kTransmitFailed = 1U << 5,  // the last command could not be queued (back-pressure, error)
};

[[nodiscard]] const char* linkFaultName(LinkFault fault) noexcept;

class LinkMonitor {
  public:
    explicit LinkMonitor(const config::CanConfig& can) noexcept;

    void onHeartbeat(std::int64_t now_ns) noexcept;
    void onState(std::int64_t now_ns) noexcept;
    // Re-evaluates the timeouts; returns the timeout bits (kNoHeartbeatYet, kHeartbeatLost,
    // kStateStale). A newly raised bit is counted once per occurrence.
    std::uint32_t evaluate(std::int64_t now_ns) noexcept;

    [[nodiscard]] std::uint64_t heartbeatLossCount() const noexcept { return heartbeat_losses_; }
    [[nodiscard]] std::uint64_t staleCount() const noexcept { return stale_events_; }
    [[nodiscard]] std::int64_t lastHeartbeatNs() const noexcept { return last_heartbeat_ns_; }
    [[nodiscard]] std::int64_t lastStateNs() const noexcept { return last_state_ns_; }

  private:
    std::int64_t heartbeat_timeout_ns_;
    std::int64_t state_timeout_ns_;
    bool heartbeat_seen_{false};
    bool state_seen_{false};
    std::int64_t last_heartbeat_ns_{0};
    std::int64_t last_state_ns_{0};
    std::uint32_t previous_{kNoHeartbeatYet};
    std::uint64_t heartbeat_losses_{0};
    std::uint64_t stale_events_{0};
};

}  // namespace haptic::devices
