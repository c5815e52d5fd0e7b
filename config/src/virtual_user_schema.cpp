#include <string>

#include "haptic/config/virtual_user.hpp"
#include "schema.hpp"

namespace haptic::config {
namespace {

HandImpedanceConfig readHandImpedance(MapReader map) {
    HandImpedanceConfig out;
    // Bounds: a finger segment's inertia is of the order of 1e-6..1e-4 kg m^2; the upper
    // stiffness bound is far beyond a clenched finger and only catches unit slips.
    out.inertia_kg_m2 = map.required("inertia_kg_m2", spec::Reals<3>{spec::Real::positive(1e-2)});
    out.stiffness_nm_per_rad =
        map.required("stiffness_nm_per_rad", spec::Reals<3>{spec::Real::positive(50.0)});
    out.damping_nms_per_rad =
        map.required("damping_nms_per_rad", spec::Reals<3>{spec::Real::closed(0.0, 5.0)});
    map.finish();
    return out;
}

UserPadConfig readUserPad(MapReader map) {
    UserPadConfig out;
    // A fingertip's radius is of the order of 5-12 mm; pad moduli of 10 kPa..10 MPa span
    // the soft pulp to a callused pad. Outside, a unit slip is likelier than a finger.
    out.radius_m = map.optional("radius_m", out.radius_m, spec::Real::closed(0.002, 0.02));
    out.effective_modulus_pa = map.optional("effective_modulus_pa", out.effective_modulus_pa,
                                            spec::Real::closed(1e4, 1e7));
    map.finish();
    return out;
}

TrackerConfig readTracker(MapReader map) {
    TrackerConfig out;
    out.topic = map.optional("topic", out.topic, spec::Text{});
    out.rate_hz = map.required("rate_hz", spec::Integer<int>::closed(1, 1000));
    out.latency_ms = map.required("latency_ms", spec::Real::closed(0.0, 1000.0));
    out.position_noise_m = map.required("position_noise_m", spec::Real::closed(0.0, 0.05));
    out.angle_noise_rad = map.required("angle_noise_rad", spec::Real::closed(0.0, 0.5));
    out.seed = map.optional("seed", out.seed, spec::Integer<std::uint32_t>::closed(0, 0xFFFFFFFFU));
    map.finish();
    return out;
}

// The user wears every device at once, so they must share one bus: one interface, or one
// UDP port block.
void checkOneBus(const std::vector<DeviceConfig>& devices, const ListReader& device_list) {
    for (std::size_t i = 1; i < devices.size(); ++i) {
        if (devices[i].can.bus() != devices.front().can.bus()) {
            device_list.at(i).fail("a device on the bus of '" + devices.front().name +
                                       "' (the virtual user wears all devices on one bus)",
                                   "'" + devices[i].name + "' on another bus");
        }
    }
}

}  // namespace

VirtualUserConfig loadVirtualUserConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    VirtualUserConfig out;
    out.source = path;
    out.log_level = detail::readLogLevel(root);
    {
        auto [scene_path, scene_field] = root.requiredWithField("scene", spec::File{});
        out.scene = loadSceneConfig(scene_path);
        if (out.scene.tracking.source == TrackingSource::kTopic) {
            scene_field.fail(
                "a scene whose tracking source is scripted or replay (the user's "
                "intent)",
                "scene '" + out.scene.name + "' tracking from a topic");
        }
    }
    out.hand_impedance = readHandImpedance(root.requiredMap("hand_impedance"));
    if (auto pad = root.optionalMap("pad")) {
        out.pad = readUserPad(std::move(*pad));
    }
    out.tracker = readTracker(root.requiredMap("tracker"));
    out.dds = detail::readDds(root);
    const ListReader device_list = detail::requiredDeviceList(root);
    out.devices = detail::readDeviceList(device_list);
    detail::checkDeviceBindings(out.scene, out.devices, device_list);
    checkOneBus(out.devices, device_list);
    root.finish();
    return out;
}

}  // namespace haptic::config
