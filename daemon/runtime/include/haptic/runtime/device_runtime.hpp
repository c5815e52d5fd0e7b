#pragma once

// Every device of daemon.yaml as hapticd's RT thread drives it, one DeviceChannel each.
// Devices that share a bus (same SocketCAN interface, same UDP port block) share one CanBus:
// read() drains each bus once (at most devices::kMaxFramesPerPoll frames per bus per tick) and
// hands every frame to the device owning its id.
//
// The tick, split the way hapticd times it (read / compute / write):
//   read(now)          CAN frames -> driver state
//   compute(core, now) the hardware E-stop input (if attached) into DaemonCore first, then
//                      link supervision and faults, rendering, safety, output gain; each
//                      device's report goes into DaemonCore (status, DeviceState, telemetry).
//                      Call it after DaemonCore::update() so the fade gain is this tick's.
//   write()            one command per device
//   writeSafe()        instead of write() when the loop ends: every device's safe command
// All three are noexcept, allocation- and lock-free after construction.

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "haptic/can/bus.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/config/device.hpp"
#include "haptic/daemon/daemon_core.hpp"
#include "haptic/devices/estop_relay_monitor.hpp"
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

    // The hardware E-stop relay (daemon.yaml estop_relay) on the bus of device `bus_device`:
    // its status frames are read with that bus's, and compute() hands its input to the core
    // before any device computes, so a press zeroes the force in the tick that reads it.
    void attachEstopRelay(std::size_t bus_device, std::uint32_t status_id, std::int64_t timeout_ns);
    [[nodiscard]] const devices::EstopRelayMonitor* estopRelay() const noexcept {
        return estop_relay_ ? &*estop_relay_ : nullptr;
    }

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
    std::optional<devices::EstopRelayMonitor> estop_relay_;
    can::CanBus* estop_bus_{nullptr};
    std::string estop_label_;  // "0x0e0 on exo's bus", for the fault message
};

// The buses daemon.yaml's devices need, opened once per distinct bus (I/O: sockets).
struct OpenedBuses {
    std::vector<std::unique_ptr<can::CanBus>> owned;
    std::vector<can::CanBus*> per_device;   // index = device index
    std::vector<std::string> descriptions;  // per device, for the log
};

// Throws std::runtime_error naming the device and the bus when one cannot be opened (no
// SocketCAN in the kernel, no such interface, no free UDP port) or two devices describe the
// same UDP port block with different slot counts. An enabled E-stop relay's status id joins
// the receive filter of its device's SocketCAN bus.
[[nodiscard]] OpenedBuses openBuses(const std::vector<config::DeviceConfig>& devices,
                                    const config::EstopRelayConfig& estop_relay = {});

}  // namespace haptic::runtime
