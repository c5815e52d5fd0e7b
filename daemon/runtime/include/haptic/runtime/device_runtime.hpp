#pragma once

// Every device of daemon.yaml as hapticd's RT thread drives it, one DeviceChannel each.
// Devices that share a bus (same SocketCAN interface, same UDP port block) share one CanBus:
// read() drains each bus once (at most devices::kMaxFramesPerPoll frames per bus per tick) and
// hands every frame to the device owning its id.
//
// The tick, split the way hapticd times it (read / compute / write):
//   read(now)          CAN frames -> driver state
//   compute(core, now) link supervision and faults, rendering, safety, output gain; each
//                      device's report goes into DaemonCore (status, DeviceState, telemetry).
//                      Call it after DaemonCore::update() so the fade gain is this tick's.
//   write()            one command per device
//   writeSafe()        instead of write() when the loop ends: every device's safe command
// All three are noexcept, allocation- and lock-free after construction.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/daemon/daemon_core.hpp"
#include "haptic/runtime/device_channel.hpp"

namespace haptic::runtime {

class DeviceRuntime {
  public:
    static constexpr std::size_t kMaxDevicesPerBus = 8;

    // buses[i] is device i's bus (devices on one bus pass the same pointer); the caller keeps
    // the buses alive. Throws std::invalid_argument on a size mismatch or invalid device
    // parameters.
    DeviceRuntime(const std::vector<config::DeviceConfig>& devices,
                  const std::vector<can::CanBus*>& buses, const ChannelSettings& settings);

    void read(std::int64_t now_ns) noexcept;
    void compute(daemon::DaemonCore& core, std::int64_t now_ns) noexcept;
    void write() noexcept;
    void writeSafe() noexcept;

    [[nodiscard]] std::size_t size() const noexcept { return channels_.size(); }
    [[nodiscard]] DeviceChannel& channel(std::size_t index) noexcept { return *channels_[index]; }
    [[nodiscard]] const DeviceChannel& channel(std::size_t index) const noexcept {
        return *channels_[index];
    }

  private:
    struct BusGroup {
        can::CanBus* bus{nullptr};
        std::array<DeviceChannel*, kMaxDevicesPerBus> members{};
        std::size_t count{0};
    };

    std::vector<std::unique_ptr<DeviceChannel>> channels_;
    std::vector<BusGroup> groups_;
};

// The buses daemon.yaml's devices need, opened once per distinct bus (I/O: sockets).
struct OpenedBuses {
    std::vector<std::unique_ptr<can::CanBus>> owned;
    std::vector<can::CanBus*> per_device;   // index = device index
    std::vector<std::string> descriptions;  // per device, for the log
};

// Throws std::runtime_error naming the device and the bus when one cannot be opened (no
// SocketCAN in the kernel, no such interface, no free UDP port) or two devices describe the
// same UDP port block with different slot counts.
[[nodiscard]] OpenedBuses openBuses(const std::vector<config::DeviceConfig>& devices);

}  // namespace haptic::runtime
