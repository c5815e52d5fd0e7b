#pragma once

// Schema pieces shared by the loaders. Private to the library.

#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "haptic/config/common.hpp"
#include "haptic/config/device.hpp"
#include "haptic/config/reader.hpp"
#include "haptic/config/scene.hpp"
#include "haptic/config/types.hpp"

namespace haptic::config::detail {

// Workspace bound for positions in scenes and calibrations: generous for a tabletop, tight
// enough to catch millimetres typed as metres.
inline constexpr double kMaxPositionM = 10.0;
// Upper bound on devices per process; matches the status message capacity.
inline constexpr std::size_t kMaxDevices = 4;

LogLevel readLogLevel(MapReader& root);
SimLinkConfig readSimLink(MapReader& root);
DdsConfig readDds(MapReader& root);
std::optional<IceoryxConfig> readIceoryx(MapReader& root);

// The transport keys daemon.yaml and sim.yaml share (sim_link, dds, iceoryx), read in that
// order into a DaemonConfig or a SimConfig.
template <class ProcessConfig>
void readTransports(MapReader& root, ProcessConfig& out) {
    out.sim_link = readSimLink(root);
    out.dds = readDds(root);
    out.iceoryx = readIceoryx(root);
}

// {position_m: [x, y, z], rpy_deg: [r, p, y]}; rpy_deg is optional and defaults to zero.
Pose readPose(MapReader map);
// {translation_m: [x, y, z], rpy_deg: [r, p, y]}; both required.
Transform readTransform(MapReader map);

// Reads one device file's root map (the body of loadDeviceConfig). With the rate of the loop
// that will render it (hapticd's loop.rate_hz), an exoskeleton's safety.max_stiffness_n_per_m
// must also pass the sampled-data passivity margin at that rate.
DeviceConfig readDevice(MapReader root, const std::filesystem::path& source,
                        std::optional<int> control_rate_hz = std::nullopt);

// The `devices: [paths]` list of daemon and sim files.
ListReader requiredDeviceList(MapReader& root);
// Loads every listed file and checks names and CAN ids across devices.
std::vector<DeviceConfig> readDeviceList(const ListReader& list,
                                         std::optional<int> control_rate_hz = std::nullopt);

// Every listed device needs a simulated finger of the scene to take its targets from (a
// binding in the scene's `devices`), and an exoskeleton needs finger joints, which the
// fingertip-only model does not have. `device_list` points the errors at the list entries.
void checkDeviceBindings(const SceneConfig& scene, const std::vector<DeviceConfig>& devices,
                         const ListReader& device_list);

}  // namespace haptic::config::detail
