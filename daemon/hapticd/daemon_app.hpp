#pragma once

#include <optional>

#include "haptic/config/command_line.hpp"
#include "haptic/config/daemon.hpp"
#include "haptic/daemon/periodic_timer.hpp"

namespace haptic::hapticd {

using DaemonOptions = config::RunOptions<config::DaemonConfig>;

// Runs hapticd until shutdown: the 1 kHz RT thread plus the non-RT status/watchdog thread
// (this one). Returns the process exit code. Throws ipc::IpcError when a transport cannot be
// set up (RouDi missing, DDS profile broken).
int runDaemon(const DaemonOptions& options);

}  // namespace haptic::hapticd
