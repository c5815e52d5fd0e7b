#include <string>

#include "haptic/config/sim.hpp"
#include "schema.hpp"

namespace haptic::config {
namespace {

// Every served device needs a simulated finger to take its targets from, and the
// exoskeleton needs finger joints, which the fingertip-only model does not have.
void checkBindings(const SceneConfig& scene, const std::vector<DeviceConfig>& devices,
                   const ListReader& device_list) {
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const DeviceConfig& device = devices[i];
        const Field entry = device_list.at(i);
        if (!scene.devices.contains(device.name)) {
            std::string bound;
            for (const auto& [name, binding] : scene.devices) {
                bound += (bound.empty() ? "" : ", ") + name;
            }
            entry.fail("a device bound in scene '" + scene.name +
                           "' (bound: " + (bound.empty() ? std::string("none") : bound) + ")",
                       "'" + device.name + "'");
        }
        if (device.isExoskeleton() && scene.hand.model == HandModel::kFingertip) {
            entry.fail("a device the scene's hand model can drive",
                       "exoskeleton '" + device.name + "' with hand.model fingertip (no joints)");
        }
    }
}

}  // namespace

SimConfig loadSimConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    SimConfig out;
    out.source = path;
    out.log_level = detail::readLogLevel(root);
    out.scene = loadSceneConfig(root.required("scene", spec::File{}));
    detail::readTransports(root, out);
    const ListReader device_list = detail::requiredDeviceList(root);
    out.devices = detail::readDeviceList(device_list);
    checkBindings(out.scene, out.devices, device_list);
    root.finish();
    return out;
}

}  // namespace haptic::config
