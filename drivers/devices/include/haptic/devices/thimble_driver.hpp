#pragma once

// Daemon-side thimble driver: three servo targets out, three measured angles in. Same RT
// contract and call order as ExoskeletonDriver.

#include <cstdint>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/devices/link_monitor.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace haptic::devices {

struct ThimbleDriverState {
    protocol::ThimbleState servos;
    std::int64_t state_time_ns{0};
    std::uint64_t state_updates{0};
    protocol::Heartbeat heartbeat;
    protocol::FaultReport last_fault;
};

class ThimbleDriver {
  public:
    // Throws std::invalid_argument when the device is not a thimble.
    ThimbleDriver(const config::DeviceConfig& device, can::CanBus& bus);

    int poll(std::int64_t now_ns) noexcept;
    bool handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept;
    // Refuses NaN/Inf and targets outside the servo range (kInvalid, counted).
    can::IoResult sendCommand(const protocol::ThimbleCommand& command) noexcept;
    [[nodiscard]] std::uint32_t faults(std::int64_t now_ns) noexcept;

    [[nodiscard]] const ThimbleDriverState& state() const noexcept { return state_; }
    [[nodiscard]] const protocol::ThimbleCodec& codec() const noexcept { return codec_; }
    [[nodiscard]] const LinkMonitor& link() const noexcept { return link_; }

  private:
    can::CanBus& bus_;
    protocol::ThimbleCodec codec_;
    LinkMonitor link_;
    ThimbleDriverState state_;
};

}  // namespace haptic::devices
