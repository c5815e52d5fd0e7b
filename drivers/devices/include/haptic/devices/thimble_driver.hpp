#pragma once

// Daemon-side thimble driver: three servo targets out, three measured angles in. Same RT
// contract and call order as ExoskeletonDriver.

#include <cstdint>

#include "haptic/devices/device_driver.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace haptic::devices {

struct ThimbleDriverState {
    protocol::ThimbleState servos;
    std::int64_t state_time_ns{0};
    std::uint64_t state_updates{0};
    protocol::Heartbeat heartbeat;
    protocol::FaultReport last_fault;
};

class ThimbleDriver
    : public DeviceDriver<ThimbleDriver, protocol::ThimbleCodec, protocol::ThimbleCommand> {
  public:
    // Throws std::invalid_argument when the device is not a thimble.
    ThimbleDriver(const config::DeviceConfig& device, can::CanBus& bus)
        : DeviceDriver(device, bus) {}

    // Returns true when the frame has one of this device's ids (accepted or rejected).
    bool handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept;

    [[nodiscard]] const ThimbleDriverState& state() const noexcept { return state_; }

  private:
    ThimbleDriverState state_;
};

}  // namespace haptic::devices
