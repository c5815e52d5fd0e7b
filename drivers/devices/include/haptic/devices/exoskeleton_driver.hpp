#pragma once

// Daemon-side exoskeleton driver: typed command/state over any CanBus.
//
// RT contract: after construction every member function is noexcept, allocation-free and
// lock-free, with bounded loops (poll() reads at most kMaxFramesPerPoll frames). The loop
// calls, once per tick: poll(now) (or handleFrame() per frame from a shared-bus dispatcher),
// then faults(now), then sendCommand(). The driver reports faults; choosing the safe
// reaction (fade out, disable) is the daemon's job.

#include <cstdint>

#include "haptic/devices/device_driver.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"

namespace haptic::devices {

struct ExoskeletonState {
    protocol::ExoskeletonActuatorState actuator;
    protocol::ExoskeletonEncoders encoders;
    std::int64_t actuator_time_ns{0};  // receive time of the frames
    std::int64_t encoders_time_ns{0};
    std::uint64_t actuator_updates{0};
    std::uint64_t encoder_updates{0};
    protocol::Heartbeat heartbeat;
    protocol::FaultReport last_fault;
};

class ExoskeletonDriver : public DeviceDriver<ExoskeletonDriver, protocol::ExoskeletonCodec,
                                              protocol::ExoskeletonCommand> {
  public:
    // Throws std::invalid_argument when the device is not an exoskeleton.
    ExoskeletonDriver(const config::DeviceConfig& device, can::CanBus& bus)
        : DeviceDriver(device, bus) {}

    // Returns true when the frame has one of this device's ids (accepted or rejected).
    bool handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept;

    [[nodiscard]] const ExoskeletonState& state() const noexcept { return state_; }

  private:
    ExoskeletonState state_;
};

}  // namespace haptic::devices
