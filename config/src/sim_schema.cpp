#include <string>

#include "haptic/config/sim.hpp"
#include "schema.hpp"

namespace haptic::config {
namespace {

TrackingFilterConfig readTrackingFilter(MapReader map) {
    using spec::Real;
    TrackingFilterConfig out;
    out.min_cutoff_hz = map.required("min_cutoff_hz", Real::closed(0.01, 100.0));
    if (auto angle_beta = map.take("angle_beta_s_per_rad")) {
        out.angle_beta_s_per_rad = Real::closed(0.0, 1000.0).parse(*angle_beta);
    }
    out.position_beta_s_per_m = map.required("position_beta_s_per_m", Real::closed(0.0, 10000.0));
    out.derivative_cutoff_hz = map.required("derivative_cutoff_hz", Real::closed(0.01, 100.0));
    map.finish();
    return out;
}

}  // namespace

SimConfig loadSimConfig(const std::filesystem::path& path) {
    MapReader root = MapReader::openFile(path);
    SimConfig out;
    out.source = path;
    out.log_level = detail::readLogLevel(root);
    out.cpu_latency_us =
        root.optional("cpu_latency_us", -1, spec::Integer<int>::closed(-1, 10'000));
    out.scene = loadSceneConfig(root.required("scene", spec::File{}));
    detail::readTransports(root, out);
    const ListReader device_list = detail::requiredDeviceList(root);
    out.devices = detail::readDeviceList(device_list);
    detail::checkDeviceBindings(out.scene, out.devices, device_list);
    if (auto filter = root.optionalMap("tracking_filter")) {
        out.tracking_filter = readTrackingFilter(std::move(*filter));
    }
    root.finish();
    return out;
}

}  // namespace haptic::config
