#pragma once

// Daemon-side exoskeleton driver: typed command/state over any CanBus.
//
// RT contract: after construction every member function is noexcept, allocation-free and
// lock-free, with bounded loops (poll() reads at most kMaxFramesPerPoll frames). The loop
// calls, once per tick: poll(now) (or handleFrame() per frame from a shared-bus dispatcher),
// then faults(now), then sendCommand(). The driver reports faults; choosing the safe
// reaction (fade out, disable) is the daemon's job.

#include <cstdint>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/devices/link_monitor.hpp"
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

class ExoskeletonDriver {
  public:
    // Throws std::invalid_argument when the device is not an exoskeleton.
    ExoskeletonDriver(const config::DeviceConfig& device, can::CanBus& bus);

    // Reads and handles pending frames (at most kMaxFramesPerPoll); frames with other ids are
    // ignored, so use handleFrame() with a dispatcher when devices share a bus.
    int poll(std::int64_t now_ns) noexcept;
    // Returns true when the frame has one of this device's ids (accepted or rejected).
    bool handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept;

    // Encodes and writes a command. Refuses NaN/Inf and forces beyond the actuator limit
    // (returns kInvalid and counts it) rather than clamping silently.
    can::IoResult sendCommand(const protocol::ExoskeletonCommand& command) noexcept;

    // Current LinkFault bits (timeouts evaluated against now_ns).
    [[nodiscard]] std::uint32_t faults(std::int64_t now_ns) noexcept;

    [[nodiscard]] const ExoskeletonState& state() const noexcept { return state_; }
    [[nodiscard]] const protocol::ExoskeletonCodec& codec() const noexcept { return codec_; }
    [[nodiscard]] const LinkMonitor& link() const noexcept { return link_; }
    // Counter carried by the most recently sent command (the device echoes it).
    [[nodiscard]] std::uint8_t lastCommandCounter() const noexcept { return last_counter_; }

  private:
    can::CanBus& bus_;
    protocol::ExoskeletonCodec codec_;
    LinkMonitor link_;
    ExoskeletonState state_;
    std::uint8_t last_counter_{0};
};

}  // namespace haptic::devices
