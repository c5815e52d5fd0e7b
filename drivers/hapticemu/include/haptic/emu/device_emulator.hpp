#pragma once

// The device side of the link: decodes commands, runs the device model, sends state,
// heartbeat and fault frames through the fault injector. It plays the part libfranka's mock
// server plays for the robot: the real frames on a real bus.
//
// Modes:
//   lockstep  every accepted command advances the model by one tick (1 ms) and is answered
//             by the state at once, so a test can predict each state frame exactly;
//   stream    the model advances on the clock and state goes out every tick, as the real
//             device does; commands only change the setpoint.
// Heartbeats follow the clock in both modes.
//
// Command timeout (can.command_timeout_ms, the device's own watchdog; docs/drivers.md), in
// stream mode (lockstep time is the command count, so no command is ever late there):
// armed by the first valid command. When no valid command has arrived for that long, the
// device goes to its safe state by itself (exoskeleton disabled at 0 N, thimble driven to its
// retract pose), reports fault 4 active (fault frame, heartbeat mode "fault", the
// exoskeleton's faulted bit) and ignores setpoints. Only a command that asks for the safe
// state acknowledges it (exoskeleton: enable bit clear; thimble: the retract pose), so a host
// that wakes up mid-stroke cannot resume the force it was sending: it must first command
// safe, as a drive needs a fault reset and a new enable.

#include <cstdint>
#include <memory>

#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/emu/fault_injector.hpp"
#include "haptic/protocol/device_codec.hpp"

namespace haptic::emu {

class ExoskeletonModel;
class ThimbleModel;

enum class EmulatorMode : std::uint8_t { kLockstep, kStream };

struct EmulatorOptions {
    EmulatorMode mode{EmulatorMode::kStream};
    std::int64_t tick_ns{1'000'000};
    std::int64_t heartbeat_period_ns{10'000'000};
};

class DeviceEmulator {
  public:
    virtual ~DeviceEmulator() = default;
    DeviceEmulator(const DeviceEmulator&) = delete;
    DeviceEmulator& operator=(const DeviceEmulator&) = delete;

    virtual void handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept = 0;
    // Heartbeat, stream ticks, fault reports and delayed frames that are due.
    void tick(std::int64_t now_ns) noexcept;

    FaultInjector& faults() noexcept { return faults_; }
    // The device's model, for the virtual user who wears it (nullptr: another kind).
    [[nodiscard]] virtual ExoskeletonModel* exoskeletonModel() noexcept { return nullptr; }
    [[nodiscard]] virtual const ThimbleModel* thimbleModel() const noexcept { return nullptr; }
    [[nodiscard]] std::uint64_t commandsAccepted() const noexcept { return commands_; }
    // Whether the command timeout holds the device safe now, and how often it tripped.
    [[nodiscard]] bool commandTimedOut() const noexcept { return timed_out_; }
    [[nodiscard]] std::uint64_t commandTimeouts() const noexcept { return timeouts_; }
    // The exoskeleton's drive, after a restart or once an injected device fault has cleared,
    // obeys no setpoint until a command with the enable bit clear, as after its command
    // timeout: the enabled force in flight before does not re-arm it. (The thimble's servos
    // follow their setpoints again: a position device, which hapticd commands along the
    // retract path while it holds its fault.)
    [[nodiscard]] bool awaitingSafeCommand() const noexcept { return awaiting_safe_command_; }
    // The fault the device reports: an injected one first, else the command timeout (4).
    [[nodiscard]] std::uint8_t activeFault() const noexcept;
    [[nodiscard]] const protocol::RejectCounters& rejects() const noexcept {
        return codec_base_.rejects();
    }

  protected:
    // What a restart or a cleared fault leaves the device waiting for before it obeys again.
    enum class ReArm { kOnAnyCommand, kOnlyOnASafeCommand };
    // `codec` must already be constructed: derived classes hold it in a base listed before
    // DeviceEmulator (base-from-member), never in a member of their own.
    DeviceEmulator(can::CanBus& bus, EmulatorOptions options, protocol::DeviceCodecBase& codec,
                   const config::DeviceConfig& device, ReArm re_arm) noexcept
        : bus_(bus),
          options_(options),
          command_timeout_ns_(static_cast<std::int64_t>(device.can.command_timeout_ms) * 1'000'000),
          re_arms_only_on_a_safe_command_(re_arm == ReArm::kOnlyOnASafeCommand),
          codec_base_(codec) {}
    virtual void stepModel(double dt_s) noexcept = 0;
    // A restart (the `reboot` fault command): the device forgets the last command.
    virtual void onReboot() noexcept = 0;
    virtual void sendState(std::int64_t now_ns) noexcept = 0;
    // A valid command arrived; `asks_safe` when it commands the safe state. Returns whether
    // its setpoint may be applied (false while the device holds its safe state: holdsSafe()).
    // Lockstep: one tick per command, then reply.
    [[nodiscard]] bool onCommandAccepted(std::int64_t now_ns, bool asks_safe) noexcept;
    void send(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
        faults_.send(bus_, frame, now_ns);
    }
    [[nodiscard]] double tickSeconds() const noexcept { return 1e-9 * options_.tick_ns; }
    // The device holds its safe state by itself: timed out, or not yet re-armed.
    [[nodiscard]] bool holdsSafe() const noexcept { return timed_out_ || awaiting_safe_command_; }

    can::CanBus& bus_;
    EmulatorOptions options_;
    FaultInjector faults_;
    std::uint64_t commands_{0};

  private:
    void checkCommandTimeout(std::int64_t now_ns) noexcept;
    void reportCommandTimeout(bool active, std::int64_t now_ns) noexcept;

    std::int64_t command_timeout_ns_;
    bool re_arms_only_on_a_safe_command_;
    std::int64_t last_command_ns_{0};
    bool command_seen_{false};
    bool timed_out_{false};
    bool awaiting_safe_command_{false};
    std::uint64_t timeouts_{0};
    protocol::DeviceCodecBase& codec_base_;
    bool started_{false};
    std::int64_t start_ns_{0};
    std::int64_t next_heartbeat_ns_{0};
    std::int64_t next_tick_ns_{0};
};

// Throws std::invalid_argument for an unknown device type.
[[nodiscard]] std::unique_ptr<DeviceEmulator> makeEmulator(const config::DeviceConfig& device,
                                                           can::CanBus& bus,
                                                           EmulatorOptions options);

}  // namespace haptic::emu
