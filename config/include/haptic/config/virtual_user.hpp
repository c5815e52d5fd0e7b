#pragma once

// The virtual user that hapticemu emulates (config/user.yaml): one model of the user's hand
// that wears every emulated device and is what the tracker sees. Its motion intent is the
// tracking block of a scene (the same scripts handsim runs, or a replay file), its index
// finger has a joint impedance towards that intent, and its actual pose goes out on the
// HandPose topic at a tracker's rate, with latency and noise. docs/drivers.md, "Virtual user".

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "haptic/config/common.hpp"
#include "haptic/config/device.hpp"
#include "haptic/config/scene.hpp"

namespace haptic::config {

// Per joint of the finger a device is worn on: MCP, PIP, DIP. The defaults are of the order
// measured for the relaxed index finger (docs/drivers.md cites the sources).
struct HandImpedanceConfig {
    std::array<double, 3> inertia_kg_m2{2.0e-5, 8.0e-6, 3.0e-6};
    std::array<double, 3> stiffness_nm_per_rad{0.30, 0.15, 0.08};
    std::array<double, 3> damping_nms_per_rad{0.004, 0.0015, 0.0008};
};

// The user's finger pad under a thimble's plate (docs/drivers.md, "Virtual user"): the distal
// phalanx of the fingertip's radius, its side in line contact with the plate and its tip a
// Hertz sphere, F = 4/3 E* sqrt(R) delta^(3/2) (emu::UserPad). It is the user's, not the
// tactile optimiser's pad law, so the felt force judges the rendering rather than restating
// its model. The defaults are the scene's
// fingertip (diameter 16 mm) and the FEM tissue's material (E 50 kPa, nu 0.45) as a half-space,
// E* = E / (1 - nu^2).
struct UserPadConfig {
    double radius_m{0.008};
    double effective_modulus_pa{6.27e4};
};

// YAML: tracker: {topic, rate_hz, latency_ms, position_noise_m, angle_noise_rad, seed}
struct TrackerConfig {
    std::string topic{"tracking/hand"};
    int rate_hz{90};
    double latency_ms{20.0};       // from the pose to its message on the topic
    double position_noise_m{0.0};  // standard deviation per wrist coordinate
    double angle_noise_rad{0.0};   // standard deviation per joint angle
    std::uint32_t seed{1};         // of the noise: runs are repeatable
};

struct VirtualUserConfig {
    std::filesystem::path source;
    LogLevel log_level{LogLevel::kInfo};
    // The scene whose hand and tracking block (scripted or replay) give the intent.
    SceneConfig scene;
    HandImpedanceConfig hand_impedance;
    UserPadConfig pad;
    TrackerConfig tracker;
    DdsConfig dds;
    // Every device the user wears; all on one bus, each bound to a finger in the scene.
    std::vector<DeviceConfig> devices;
};

// Loads user.yaml, its scene and its device files. Throws ConfigError.
[[nodiscard]] VirtualUserConfig loadVirtualUserConfig(const std::filesystem::path& path);

}  // namespace haptic::config
