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
    [[nodiscard]] const protocol::RejectCounters& rejects() const noexcept {
        return codec_base_.rejects();
    }

  protected:
    // `codec` must already be constructed: derived classes hold it in a base listed before
    // DeviceEmulator (base-from-member), never in a member of their own.
    DeviceEmulator(can::CanBus& bus, EmulatorOptions options,
                   protocol::DeviceCodecBase& codec) noexcept
        : bus_(bus), options_(options), codec_base_(codec) {}
    virtual void stepModel(double dt_s) noexcept = 0;
    virtual void sendState(std::int64_t now_ns) noexcept = 0;
    // Lockstep: one tick per command, then reply.
    void onCommandAccepted(std::int64_t now_ns) noexcept;
    void send(const can::CanFrame& frame, std::int64_t now_ns) noexcept {
        faults_.send(bus_, frame, now_ns);
    }
    [[nodiscard]] double tickSeconds() const noexcept { return 1e-9 * options_.tick_ns; }

    can::CanBus& bus_;
    EmulatorOptions options_;
    FaultInjector faults_;
    std::uint64_t commands_{0};

  private:
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
