#include "haptic/runtime/device_channel.hpp"

#include <array>
#include <cstdio>

#include "haptic/protocol/frame_codec.hpp"

namespace haptic::runtime {
namespace {

// Faults that stop the link: the device cannot be driven until an operator clears them.
constexpr std::uint32_t kLatchingFaults = devices::kHeartbeatLost | devices::kBusOff |
                                          devices::kDeviceFault | devices::kTransmitFailed |
                                          devices::kDeviceRebooted | kImplausibleFeedback;
// Faults that hold the device safe while present, latched or not.
constexpr std::uint32_t kHoldSafe = kLatchingFaults | devices::kNoHeartbeatYet;

msgs::BusState toMessage(can::BusState state) noexcept {
    switch (state) {
        case can::BusState::kErrorActive:
            return msgs::BusState::kErrorActive;
        case can::BusState::kErrorWarning:
            return msgs::BusState::kErrorWarning;
        case can::BusState::kErrorPassive:
            return msgs::BusState::kErrorPassive;
        case can::BusState::kBusOff:
            return msgs::BusState::kBusOff;
    }
    return msgs::BusState::kUnknown;
}

const char* deviceFaultName(std::uint8_t code) noexcept {
    switch (code) {
        case 1:
            return "overcurrent";
        case 2:
            return "overtemperature";
        case 3:
            return "position limit";
        case 4:
            return "command timeout";
        case 5:
            return "encoder";
        case 6:
            return "internal";
        default:
            return "unknown";
    }
}

constexpr std::uint32_t bit(msgs::DeviceStatusBit b) noexcept {
    return static_cast<std::uint32_t>(b);
}

}  // namespace

DeviceChannel::DeviceChannel(const config::DeviceConfig& device, can::CanBus& bus,
                             const ChannelSettings& settings)
    : settings_(settings),
      name_(device.name),
      bus_(bus),
      heartbeat_timeout_ms_(device.can.heartbeat_timeout_ms),
      heartbeat_timeout_ns_(static_cast<std::int64_t>(device.can.heartbeat_timeout_ms) *
                            1'000'000) {}

bool DeviceChannel::handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
    if (!driverHandleFrame(frame, now_ns)) {
        return false;
    }
    ++rx_frames_;
    return true;
}

bool DeviceChannel::heldSafe() const noexcept {
    return latched_ != 0 || (link_bits_ & kHoldSafe) != 0;
}

namespace {

// The code each fault bit is raised with.
std::uint32_t faultCodeOf(std::uint32_t fault_bit) noexcept {
    switch (fault_bit) {
        case devices::kHeartbeatLost:
            return kFaultHeartbeatLost;
        case devices::kBusOff:
            return kFaultBusOff;
        case devices::kDeviceFault:
            return kFaultDeviceReported;
        case devices::kDeviceRebooted:
            return kFaultDeviceRebooted;
        case kImplausibleFeedback:
            return kFaultImplausibleFeedback;
        default:
            return kFaultTransmitFailed;
    }
}

// The latching fault bits, in the order they are raised (and a standing cause is named).
constexpr std::array<std::uint32_t, 6> kFaultBitsInOrder{
    devices::kHeartbeatLost,  devices::kBusOff,         devices::kDeviceFault,
    devices::kTransmitFailed, devices::kDeviceRebooted, kImplausibleFeedback};

}  // namespace

void DeviceChannel::raise(daemon::DaemonCore& core, std::uint32_t fault_bit) noexcept {
    // snprintf into a stack buffer: no allocation on the RT thread.
    char message[msgs::kShortTextCapacity];
    switch (fault_bit) {
        case devices::kHeartbeatLost:
            std::snprintf(message, sizeof(message),
                          "heartbeat lost: none for more than %d ms; device held safe",
                          heartbeat_timeout_ms_);
            break;
        case devices::kBusOff:
            std::snprintf(message, sizeof(message),
                          "CAN bus-off: controller refuses to transmit; device held safe");
            break;
        case devices::kDeviceFault: {
            const std::uint8_t reported = deviceFaultCode();
            std::snprintf(message, sizeof(message), "device reports fault %u (%s); held safe",
                          static_cast<unsigned>(reported), deviceFaultName(reported));
            break;
        }
        case devices::kDeviceRebooted:
            std::snprintf(message, sizeof(message),
                          "device rebooted (uptime %u ms after %u ms); held safe",
                          static_cast<unsigned>(link().uptimeAfterRebootMs()),
                          static_cast<unsigned>(link().uptimeBeforeRebootMs()));
            break;
        case kImplausibleFeedback:
            std::snprintf(message, sizeof(message), "%s; held safe", implausibleMessage());
            break;
        default:
            std::snprintf(message, sizeof(message),
                          "CAN transmit failed %d ticks in a row; device held safe",
                          settings_.transmit_fault_ticks);
            break;
    }
    core.raiseFault(faultCodeOf(fault_bit), name_, message);
}

void DeviceChannel::supervise(daemon::DaemonCore& core, std::int64_t now_ns) noexcept {
    link_bits_ = driverFaults(now_ns) & ~devices::kTransmitFailed;
    link_bits_ |= plausibilityFaults(now_ns);  // may read this tick's linkFaults()
    if (failed_transmits_ >= settings_.transmit_fault_ticks) {
        link_bits_ |= devices::kTransmitFailed;
    }
    // `clear` emptied the list: re-arm, so a cause that is still there is raised again.
    if (latched_ != 0 && core.stateMachine().faultCount() == 0) {
        latched_ = 0;
    }
    if (first_supervise_ns_ == 0) {
        first_supervise_ns_ = now_ns;
    }
    if (linkStateFresh()) {
        last_fresh_ns_ = now_ns;
    }
    state_lost_ = now_ns - (last_fresh_ns_ > 0 ? last_fresh_ns_ : first_supervise_ns_) >
                  heartbeat_timeout_ns_;
    std::uint32_t active = link_bits_ & kLatchingFaults;
    // A command timeout the device reports within heartbeat_timeout_ms of this daemon's first
    // command is the silence of the host before it (a crashed or stopped hapticd): the device
    // is already safe, and the safe command this channel sends while it is held safe
    // acknowledges it. Raising it would make a restarted daemon come up in FAULT for a stop
    // that was handled. Any later one, and every other device fault, latches.
    // Likewise one reported within heartbeat_timeout_ms after this daemon's own loop stalled:
    // the stall is raised as hapticd's fault (kFaultLoopStalled), the device only obeyed it.
    const bool after_own_silence =
        now_ns - first_supervise_ns_ <= heartbeat_timeout_ns_ ||
        (core.lastStallEndNs() > 0 && now_ns - core.lastStallEndNs() <= heartbeat_timeout_ns_);
    if ((active & devices::kDeviceFault) != 0 &&
        deviceFaultCode() ==
            static_cast<std::uint8_t>(protocol::DeviceFaultCode::kCommandTimeout) &&
        after_own_silence) {
        active &= ~static_cast<std::uint32_t>(devices::kDeviceFault);
    }
    // A cause the device still shows: `clear` is refused while it lasts (a device reboot is
    // an event, not a standing cause).
    report_.standing_fault = 0;
    const std::uint32_t raised = active & ~latched_;
    for (const std::uint32_t fault_bit : kFaultBitsInOrder) {
        if ((active & fault_bit) != 0 && report_.standing_fault == 0 &&
            fault_bit != devices::kDeviceRebooted) {
            report_.standing_fault = faultCodeOf(fault_bit);
        }
        if ((raised & fault_bit) != 0) {
            raise(core, fault_bit);
        }
    }
    latched_ |= active;
    // A raised 105 stands until its contradiction has ended, not only while it is reported
    // (the report drops on each plausible tick of an intermittent cause).
    if (report_.standing_fault == 0 && (latched_ & kImplausibleFeedback) != 0 &&
        contradictionPending()) {
        report_.standing_fault = kFaultImplausibleFeedback;
    }
}

void DeviceChannel::write() noexcept {
    const can::IoResult result = sendCommand();
    if (result == can::IoResult::kOk) {
        ++tx_frames_;
        failed_transmits_ = 0;
    } else if (result == can::IoResult::kBusOff) {
        ++tx_errors_;  // bus-off is its own fault; the refused writes are its consequence
    } else {
        ++tx_errors_;
        ++failed_transmits_;
    }
}

void DeviceChannel::fillLinkReport(msgs::DaemonState state, double gain,
                                   std::int64_t now_ns) noexcept {
    const bool rendering = state == msgs::DaemonState::kRendering;
    report_.attached = true;
    if (latched_ != 0) {
        report_.run_state = msgs::DeviceRunState::kFault;
    } else if ((link_bits_ & devices::kNoHeartbeatYet) != 0) {
        report_.run_state = msgs::DeviceRunState::kOffline;
    } else if ((link_bits_ & (kHoldSafe | devices::kStateStale)) != 0 ||
               (rendering && gain <= 0.0)) {
        report_.run_state = msgs::DeviceRunState::kSafe;
    } else if (rendering) {
        report_.run_state = msgs::DeviceRunState::kActive;
    } else if (state == msgs::DaemonState::kIdle) {
        report_.run_state = msgs::DeviceRunState::kReady;
    } else {
        report_.run_state = msgs::DeviceRunState::kSafe;  // FAULT, E-STOP (or INIT)
    }

    std::uint32_t bits = 0;
    if ((link_bits_ & (devices::kNoHeartbeatYet | devices::kHeartbeatLost)) == 0) {
        bits |= bit(msgs::DeviceStatusBit::kOnline);
    }
    if (gain <= 0.0) {
        bits |= bit(msgs::DeviceStatusBit::kSafeState);
    }
    if (latched_ != 0) {
        bits |= bit(msgs::DeviceStatusBit::kFault);
    }
    report_.status_bits = bits;

    const auto& link = this->link();
    const std::int64_t last_frame_ns =
        link.lastHeartbeatNs() > link.lastStateNs() ? link.lastHeartbeatNs() : link.lastStateNs();
    report_.last_frame_age_ms =
        last_frame_ns > 0 ? static_cast<double>(now_ns - last_frame_ns) * 1e-6 : -1.0;

    const can::BusCounters& counters = bus_.counters();
    report_.can.bus_state = toMessage(bus_.state());
    report_.can.rx_frames = rx_frames_;
    report_.can.tx_frames = tx_frames_;
    // Receive errors belong to the bus (shared by its devices): error frames, malformed
    // datagrams and kernel overflows.
    report_.can.rx_errors = counters.rx_error_frames + counters.rx_dropped + counters.rx_overflows;
    report_.can.tx_errors = tx_errors_;
    report_.can.rejected_frames = rejectedFrames();
}

}  // namespace haptic::runtime
