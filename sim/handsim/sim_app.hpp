#pragma once

#include "haptic/config/command_line.hpp"
#include "haptic/config/sim.hpp"

namespace haptic::handsim {

using SimOptions = config::RunOptions<config::SimConfig>;

// Steps the scene at its rate and publishes each device's targets. Returns the exit code;
// throws ipc::IpcError when a transport cannot be set up.
int runSim(const SimOptions& options);

}  // namespace haptic::handsim
