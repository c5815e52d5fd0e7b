#pragma once

#include <vector>

#include "haptic/config/command_line.hpp"
#include "haptic/config/sim.hpp"
#include "haptic/softhand/scene_simulation.hpp"

namespace haptic::handsim {

using SimOptions = config::RunOptions<config::SimConfig>;

// The devices of sim.yaml as the soft hand sees them: the finger each is bound to in the
// scene (devices.<name>.finger), and what it needs (constraints for an exoskeleton, pad
// samples for a thimble). Throws std::invalid_argument for a device the scene does not bind.
[[nodiscard]] std::vector<softhand::DeviceRequest> deviceRequests(const config::SimConfig& cfg);

// Steps the scene at its rate and publishes each device's targets. Returns the exit code;
// throws ipc::IpcError when a transport cannot be set up.
int runSim(const SimOptions& options);

}  // namespace haptic::handsim
