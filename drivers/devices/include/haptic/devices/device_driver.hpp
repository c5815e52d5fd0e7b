#pragma once

// What every daemon-side device driver shares: its bus, codec and link monitor, the poll over
// the bus, the command write (whose counter the device echoes) and the link's fault bits. The
// device kinds differ only in how they file the frames they decode (`Derived::handleFrame`).
//
// RT contract: after construction every member function is noexcept, allocation-free and
// lock-free, with bounded loops (poll() reads at most kMaxFramesPerPoll frames).

#include <cstdint>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/devices/link_monitor.hpp"
#include "haptic/protocol/device_codec.hpp"

namespace haptic::devices {

template <class Derived, class Codec, class Command>
class DeviceDriver {
  public:
    // Reads and handles pending frames (at most kMaxFramesPerPoll); frames with other ids are
    // ignored, so use handleFrame() with a dispatcher when devices share a bus.
    int poll(std::int64_t now_ns) noexcept {
        return pollFrames(bus_, now_ns, [this](const can::CanFrame& frame, std::int64_t now) {
            return static_cast<Derived*>(this)->handleFrame(frame, now);
        });
    }

    // Encodes and writes a command. Refuses NaN/Inf and values beyond the device's limits
    // (returns kInvalid and counts it) rather than clamping silently.
    can::IoResult sendCommand(const Command& command) noexcept {
        const std::uint8_t counter = codec_.peekCounter(protocol::FrameRole::kCommand);
        can::CanFrame frame;
        if (!codec_.encodeCommand(command, frame)) {
            return can::IoResult::kInvalid;
        }
        const can::IoResult result = bus_.write(frame);
        link_.onTransmit(result);
        if (result == can::IoResult::kOk) {
            last_counter_ = counter;
        }
        return result;
    }

    // Current LinkFault bits (timeouts evaluated against now_ns).
    [[nodiscard]] std::uint32_t faults(std::int64_t now_ns) noexcept {
        return link_.faults(now_ns, bus_.state());
    }

    [[nodiscard]] const Codec& codec() const noexcept { return codec_; }
    [[nodiscard]] const LinkMonitor& link() const noexcept { return link_; }
    // Counter carried by the most recently sent command (the device echoes it).
    [[nodiscard]] std::uint8_t lastCommandCounter() const noexcept { return last_counter_; }

  protected:
    DeviceDriver(const config::DeviceConfig& device, can::CanBus& bus)
        : bus_(bus), codec_(device), link_(device.can) {}

    can::CanBus& bus_;
    Codec codec_;
    LinkMonitor link_;

  private:
    std::uint8_t last_counter_{0};
};

}  // namespace haptic::devices
