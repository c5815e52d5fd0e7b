#pragma once

// One device as hapticd's RT thread drives it: its CAN driver, its renderer and its safety
// stage, between DaemonCore (sim input, state machine, output gain) and the bus. No I/O of its
// own beyond the CanBus it is given; after construction every member the loop calls is
// noexcept, allocation- and lock-free with bounded work, so tests drive it on a LoopbackBus.
//
// Per tick (DeviceRuntime calls these in this order):
//   handleFrame()  for every frame the bus delivered (read phase)
//   supervise()    link faults -> DaemonCore::raiseFault, once per occurrence (latched)
//   compute()      renderer -> safety -> x DaemonCore::outputGain -> next command
//   write()        command to the bus
// writeSafe() replaces write() on the way out: it sends the device's safe command (exoskeleton
// disabled at 0 N, thimble at its retract pose) whatever the renderer last computed.
//
// Faults (haptic/status "Faults:", code in brackets) latch the device in its safe state:
//   100 heartbeat lost   no heartbeat for can.heartbeat_timeout_ms after one was heard
//   101 bus-off          the CAN controller reports bus-off
//   102 device fault     the device reports a fault (fault frame or heartbeat mode); a
//                        command timeout (4) reported within heartbeat_timeout_ms of the
//                        daemon's start is the previous host's and only acknowledged
//   103 transmit failed  commands could not be queued for transmit_fault_ticks ticks in a row
// A device never heard from is OFFLINE (held safe, not a fault: hapticd may start before the
// devices). A stale state frame (can.state_timeout_ms) fades the force out through the port
// guard without a fault. `clear` empties the fault list; a cause still present is raised again
// on the next tick.

#include <cstdint>
#include <string>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/daemon/daemon_core.hpp"
#include "haptic/daemon/device_report.hpp"
#include "haptic/devices/link_monitor.hpp"

namespace haptic::runtime {

// The daemon's own fault codes in haptic/status (msgs::Fault::code), raised by the channel
// about a device link. Numbered from 100 so they never meet the codes a device reports in
// its own fault frames (protocol::DeviceFaultCode, 1-6), which kFaultDeviceReported carries
// in its message.
enum DaemonFaultCode : std::uint32_t {
    kFaultHeartbeatLost = 100,
    kFaultBusOff = 101,
    kFaultDeviceReported = 102,
    kFaultTransmitFailed = 103,
    kFaultDeviceRebooted = 104,       // a heartbeat's uptime went back
    kFaultImplausibleFeedback = 105,  // the device's feedback contradicts the command
};

// A channel's own fault bit next to devices::LinkFault's: the device's feedback contradicts
// what it was commanded (the message says how); set by the device type's checks.
inline constexpr std::uint32_t kImplausibleFeedback = 1U << 16;

struct ChannelSettings {
    double period_s{1e-3};
    // Consecutive ticks whose command could not be queued (back-pressure, refusal) before the
    // link counts as failed. One refused frame is back-pressure, not a fault.
    int transmit_fault_ticks{10};
};

class DeviceChannel {
  public:
    virtual ~DeviceChannel() = default;
    DeviceChannel(const DeviceChannel&) = delete;
    DeviceChannel& operator=(const DeviceChannel&) = delete;

    [[nodiscard]] const std::string& name() const noexcept { return name_; }
    [[nodiscard]] can::CanBus& bus() noexcept { return bus_; }

    // True when the frame carries one of this device's ids (accepted or rejected).
    bool handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept;
    void supervise(daemon::DaemonCore& core, std::int64_t now_ns) noexcept;
    virtual void compute(daemon::DaemonCore& core, std::size_t index,
                         std::int64_t now_ns) noexcept = 0;
    void write() noexcept;
    // The safe command (exoskeleton disabled at 0 N, thimble retracted), written at once.
    void writeSafe() noexcept {
        commandSafe();
        write();
    }

    [[nodiscard]] const daemon::DeviceReport& report() const noexcept { return report_; }
    // LinkFault bits of the last supervise().
    [[nodiscard]] std::uint32_t linkFaults() const noexcept { return link_bits_; }
    // Whether this tick's link bits let the device's last state be trusted: heard, and neither
    // its state nor its heartbeat timed out.
    [[nodiscard]] bool linkStateFresh() const noexcept {
        return (link_bits_ &
                (devices::kStateStale | devices::kNoHeartbeatYet | devices::kHeartbeatLost)) == 0;
    }
    // LinkFault bits that raised a fault and hold the device safe until `clear`.
    [[nodiscard]] std::uint32_t latchedFaults() const noexcept { return latched_; }
    // Whether the device must send no force (thimble: retract), whatever the daemon state.
    [[nodiscard]] bool heldSafe() const noexcept;
    // Whether, at the last supervise(), the device's state had not been fresh for longer than
    // its can.heartbeat_timeout_ms (counted from the first supervise() if it never was): a
    // device lost, not a late frame.
    [[nodiscard]] bool stateLost() const noexcept { return state_lost_; }

  protected:
    DeviceChannel(const config::DeviceConfig& device, can::CanBus& bus,
                  const ChannelSettings& settings);

    virtual bool driverHandleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept = 0;
    virtual std::uint32_t driverFaults(std::int64_t now_ns) noexcept = 0;
    // kImplausibleFeedback when the device's feedback has contradicted its command for longer
    // than can.heartbeat_timeout_ms on most ticks (ContradictionTimer; then
    // implausibleMessage() says how); 0 by default.
    virtual std::uint32_t plausibilityFaults(std::int64_t /*now_ns*/) noexcept { return 0; }
    // Whether a plausibility check's contradiction has not ended yet (its balance is at or
    // above zero, ContradictionTimer::contradicting()): a raised 105 stands, and `clear` is
    // refused, until it has. So an intermittent cause cannot be cleared between two of its
    // frames, and after a repair (the balance drains within one can.heartbeat_timeout_ms)
    // nothing of the old contradiction is left to add to the operator's enable.
    [[nodiscard]] virtual bool contradictionPending() const noexcept { return false; }
    [[nodiscard]] virtual const char* implausibleMessage() const noexcept { return ""; }
    [[nodiscard]] std::int64_t heartbeatTimeoutNs() const noexcept { return heartbeat_timeout_ns_; }
    virtual can::IoResult sendCommand() noexcept = 0;
    // Sets the command the next write() sends to the device's safe state.
    virtual void commandSafe() noexcept = 0;
    [[nodiscard]] virtual const devices::LinkMonitor& link() const noexcept = 0;
    [[nodiscard]] virtual std::uint64_t rejectedFrames() const noexcept = 0;
    // The code the device reports (fault frame or heartbeat), 0 if none.
    [[nodiscard]] virtual std::uint8_t deviceFaultCode() const noexcept = 0;

    // Run state, status bits, bus counters and frame age of report_ for this tick.
    // READY: heard, healthy, daemon IDLE. ACTIVE: rendering with a gain above zero. SAFE:
    // held at zero force / retracted (stale state, stale sim input, FAULT or E-STOP of the
    // daemon). FAULT: this device's own latched fault. OFFLINE: never heard from.
    void fillLinkReport(msgs::DaemonState state, double gain, std::int64_t now_ns) noexcept;

    ChannelSettings settings_;
    daemon::DeviceReport report_{};

  private:
    void raise(daemon::DaemonCore& core, std::uint32_t bit) noexcept;

    std::string name_;
    can::CanBus& bus_;
    int heartbeat_timeout_ms_;
    std::int64_t heartbeat_timeout_ns_;
    std::int64_t first_supervise_ns_{0};
    std::int64_t last_fresh_ns_{0};  // the last supervise() whose link state was fresh
    bool state_lost_{false};
    std::uint32_t link_bits_{devices::kNoHeartbeatYet};
    std::uint32_t latched_{0};
    int failed_transmits_{0};
    std::uint64_t rx_frames_{0};
    std::uint64_t tx_frames_{0};
    std::uint64_t tx_errors_{0};
};

// The driver half of a channel, the same for every device type: it owns the device's driver
// and the command written each tick, and answers DeviceChannel's driver hooks from them.
template <typename Driver, typename Command>
class DriverChannel : public DeviceChannel {
  public:
    [[nodiscard]] const Command& command() const noexcept { return command_; }
    [[nodiscard]] const Driver& driver() const noexcept { return driver_; }

  protected:
    DriverChannel(const config::DeviceConfig& device, can::CanBus& bus,
                  const ChannelSettings& settings)
        : DeviceChannel(device, bus, settings), driver_(device, bus) {}

    bool driverHandleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept override {
        return driver_.handleFrame(frame, now_ns);
    }
    std::uint32_t driverFaults(std::int64_t now_ns) noexcept override {
        return driver_.faults(now_ns);
    }
    can::IoResult sendCommand() noexcept override { return driver_.sendCommand(command_); }
    [[nodiscard]] const devices::LinkMonitor& link() const noexcept override {
        return driver_.link();
    }
    [[nodiscard]] std::uint64_t rejectedFrames() const noexcept override {
        return driver_.codec().rejects().total();
    }
    [[nodiscard]] std::uint8_t deviceFaultCode() const noexcept override {
        const auto& state = driver_.state();
        if (state.last_fault.active) {
            return static_cast<std::uint8_t>(state.last_fault.code);
        }
        if (state.heartbeat.active_fault != 0) {
            return state.heartbeat.active_fault;
        }
        // A fault seen and gone within this poll is still raised (LinkMonitor): name what it
        // was. Only then: a code kept after the fault cleared would read as a standing fault.
        return (linkFaults() & devices::kDeviceFault) != 0 ? driver_.link().lastFaultCode() : 0;
    }

    Driver driver_;
    Command command_{};
};

}  // namespace haptic::runtime
