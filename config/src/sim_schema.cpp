#include <string>

#include "haptic/config/sim.hpp"
#include "schema.hpp"

namespace haptic::config {

SimConfig loadSimConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    SimConfig out;
    out.source = path;
    out.log_level = detail::readLogLevel(root);
    out.scene = loadSceneConfig(root.required("scene", spec::File{}));
    detail::readTransports(root, out);
    const ListReader device_list = detail::requiredDeviceList(root);
    out.devices = detail::readDeviceList(device_list);
    detail::checkDeviceBindings(out.scene, out.devices, device_list);
    root.finish();
    return out;
}

}  // namespace haptic::config
