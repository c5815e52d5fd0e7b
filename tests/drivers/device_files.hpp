#pragma once

#include <string>

#include "haptic/config/device.hpp"

namespace haptic::testing {

inline config::DeviceConfig exoskeletonDevice() {
    return config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml");
}
inline config::DeviceConfig thimbleDevice() {
    return config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/thimble.yaml");
}

}  // namespace haptic::testing
