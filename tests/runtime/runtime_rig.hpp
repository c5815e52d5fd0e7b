#pragma once

// The whole per-tick path of hapticd without RouDi or DDS: DaemonCore, the DeviceRuntime with
// the real drivers and renderers on a LoopbackBus, and the hapticemu emulator library for
// both shipped devices on the other end. Time is synthetic (1 ms per tick), so tests are
// exact and fast.

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "haptic/can/loopback_bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/daemon/daemon_core.hpp"
#include "haptic/emu/device_emulator.hpp"
#include "haptic/emu/estop_relay_emulator.hpp"
#include "haptic/runtime/device_runtime.hpp"

namespace haptic::testing {

inline constexpr std::int64_t kMs = 1'000'000;
inline constexpr std::size_t kExo = 0;
inline constexpr std::size_t kThimble = 1;
inline constexpr std::uint32_t kEstopRelayId = 0x0E0;

class RuntimeRig {
  public:
    RuntimeRig();
    // The shipped devices, changed by `adjust` before anything is built from them.
    explicit RuntimeRig(const std::function<void(std::vector<config::DeviceConfig>&)>& adjust);

    // One 1 kHz tick: emulators, bus, then hapticd's read / update / compute / write order.
    void tick();
    void ticks(int count) {
        for (int i = 0; i < count; ++i) {
            tick();
        }
    }
    // Time passes for the devices only: hapticd is stalled, stopped or not started.
    void devicesOnly(int milliseconds);
    // One millisecond for the emulated devices: they take what the bus holds, then tick.
    void advanceDevices();
    // Sim input as handsim would send it (valid; contact on both devices).
    void offerContact();
    bool command(msgs::CommandKind kind, const char* argument = "");
    // An E-stop relay on the devices' bus (status kEstopRelayId, 30 ms timeout), emulated and
    // supervised from the next tick on.
    void attachEstopRelay();
    void emulatorFault(std::size_t device, const char* line);

    [[nodiscard]] double exoForce() const;
    [[nodiscard]] std::array<double, 3> thimbleTargets() const;

    std::vector<config::DeviceConfig> devices;
    can::LoopbackBus host;
    can::LoopbackBus target;
    std::vector<std::unique_ptr<emu::DeviceEmulator>> emulators;
    std::unique_ptr<emu::EstopRelayEmulator> estop_relay;
    daemon::DaemonCore core;
    runtime::DeviceRuntime runtime;
    msgs::ConstraintSet constraint_set{};
    msgs::ContactSurface contact_surface{};
    msgs::HapticStatus status{};
    msgs::TelemetrySample telemetry{};
    msgs::DeviceState device_state{};
    msgs::HapticCommand command_scratch{};
    msgs::HapticCommandReply reply{};
    std::int64_t now{1'000 * kMs};
    std::uint64_t tick_count{0};
};

// Enables rendering and runs until the exoskeleton's force has ramped up (100 ms fade-in),
// contact offered at 100 Hz.
void renderWithContact(RuntimeRig& rig);
// Euclidean distance between two sets of servo angles.
[[nodiscard]] double distance(const std::array<double, 3>& a, const std::array<double, 3>& b);
// The thimble channel's retract angles.
[[nodiscard]] const std::array<double, 3>& retract(RuntimeRig& rig);

}  // namespace haptic::testing
