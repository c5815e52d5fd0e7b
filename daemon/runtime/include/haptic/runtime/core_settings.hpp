#pragma once

// What hapticd's DaemonCore is built from: the loop's keys of daemon.yaml (rates, timeouts,
// overrun and re-arm limits, the sim transport) and the devices it drives. Kept apart from
// hapticd's process code so that a test can show each key reaching the core.

#include <string_view>
#include <vector>

#include "haptic/config/daemon.hpp"
#include "haptic/daemon/daemon_core.hpp"

namespace haptic::runtime {

// `version` is the daemon's own, for haptic/status.
[[nodiscard]] daemon::CoreSettings coreSettings(const config::DaemonConfig& cfg,
                                                std::string_view version);
[[nodiscard]] std::vector<daemon::DeviceDescriptor> deviceDescriptors(
    const config::DaemonConfig& cfg);

}  // namespace haptic::runtime
