#pragma once

#include "haptic/config/sim.hpp"

namespace haptic::handsim {

struct SimOptions {
    config::SimConfig config;
    double duration_s{0.0};  // 0 = until SIGINT/SIGTERM
};

// Steps the scene at its rate and publishes each device's targets. Returns the exit code;
// throws ipc::IpcError when a transport cannot be set up.
int runSim(const SimOptions& options);

}  // namespace haptic::handsim
