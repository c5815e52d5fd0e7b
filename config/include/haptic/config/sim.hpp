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

// YAML: tracking_filter: {...} (optional; absent: poses are used as the tracker sends them).
// The One Euro filter handsim applies to poses from a HandPose topic, i.e. a real tracker
// (haptic/softhand/tracking_filter.hpp).
struct TrackingFilterConfig {
    double min_cutoff_hz{1.0};  // cutoff at rest
    // Cutoff rise per rad/s of a flexion angle or the wrist's rotation. Absent: the angles and
    // the wrist's orientation pass as tracked and only the wrist position is filtered.
    std::optional<double> angle_beta_s_per_rad;
    double position_beta_s_per_m{0.0};  // cutoff rise per m/s of the wrist
    double derivative_cutoff_hz{1.0};   // low-pass of the speed that sets the cutoff
};

struct SimConfig {
    std::filesystem::path source;
    LogLevel log_level{LogLevel::kInfo};
    SceneConfig scene;
    SimLinkConfig sim_link;
    DdsConfig dds;
    std::optional<IceoryxConfig> iceoryx;
    std::vector<DeviceConfig> devices;  // the devices the sim computes targets for
    std::optional<TrackingFilterConfig> tracking_filter;
    // The CPUs' wake-up latency handsim holds while it runs (/dev/cpu_dma_latency), -1: none.
    int cpu_latency_us{-1};
};

// Loads sim.yaml, its scene and its device files. Throws ConfigError.
[[nodiscard]] SimConfig loadSimConfig(const std::filesystem::path& path);

}  // namespace haptic::config
