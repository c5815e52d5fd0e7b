#pragma once

// handsim's configuration (config/sim.yaml). Loading it also loads the scene and the device
// files it lists, and checks that every device is bound to a finger the scene simulates.

#include <filesystem>
#include <optional>
#include <vector>

#include "haptic/config/common.hpp"
#include "haptic/config/device.hpp"
#include "haptic/config/scene.hpp"

namespace haptic::config {

struct SimConfig {
    std::filesystem::path source;
    LogLevel log_level{LogLevel::kInfo};
    SceneConfig scene;
    SimLinkConfig sim_link;
    DdsConfig dds;
    std::optional<IceoryxConfig> iceoryx;
    std::vector<DeviceConfig> devices;  // the devices the sim computes targets for
};

// Loads sim.yaml, its scene and its device files. Throws ConfigError.
[[nodiscard]] SimConfig loadSimConfig(const std::filesystem::path& path);

}  // namespace haptic::config
