#pragma once

// The daemon-side driver against hapticemu (a separate process, lockstep mode) on any bus:
// N command/state round trips with every state frame compared to a reference model run in
// this process, then the emulator's heartbeat is stopped and the driver must report it.
// Shared by the UDP test (host) and the SocketCAN test (vcan, in the guest or on a lab PC).

#include "emulator_process.hpp"
#include "haptic/can/bus.hpp"
#include "haptic/config/device.hpp"

namespace haptic::testing {

inline constexpr int kRoundTrips = 10'000;

void runExoskeletonScenario(can::CanBus& bus, const config::DeviceConfig& device,
                            EmulatorProcess& emulator, int round_trips);
void runThimbleScenario(can::CanBus& bus, const config::DeviceConfig& device,
                        EmulatorProcess& emulator, int round_trips);

}  // namespace haptic::testing
